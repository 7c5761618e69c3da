#pragma once

#include <string>

#include "rebraid/core/scene.h"

namespace rebraid {

/// Writes `scene` as glTF 2.0: a binary .glb (one file) or a .gltf (JSON) with its buffer in
/// a .bin file of the same stem beside it, chosen by the extension of `path` (case-insensitive).
///
/// Layout, so load_gltf_scene() gives the scene back unchanged: one glTF mesh per
/// rebraid::Mesh (same order and name, one TRIANGLES primitive with float POSITION and
/// unsigned short or int indices), one node per instance with a column-major `matrix` holding
/// the instance's transform, all nodes roots of scene 0 in instance order. Positions, indices
/// and transforms are stored exactly (floats are written with enough digits to round-trip).
///
/// Throws rebraid::Error naming the path when the scene is invalid (Scene::validate()), has no
/// instances or a mesh without triangles (glTF cannot express these), the extension is neither
/// .glb nor .gltf, the buffer exceeds glTF's 4 GiB, or the file cannot be written.
void write_gltf_scene(const Scene& scene, const std::string& path);

}  // namespace rebraid
