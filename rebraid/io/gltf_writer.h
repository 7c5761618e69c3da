#pragma once

#include <string>

#include "rebraid/core/scene.h"

namespace rebraid {

/// How write_gltf_scene() stores instances.
struct GltfWriteSettings {
    /// false: one node with a `matrix` per instance (transforms stored exactly); true: runs
    /// of instances of one mesh as EXT_mesh_gpu_instancing nodes (small files for many
    /// instances).
    bool gpu_instancing = false;
};

/// Writes `scene` as glTF 2.0: a binary .glb (one file) or a .gltf (JSON) with its buffer in
/// a .bin file of the same stem beside it, chosen by the extension of `path` (case-insensitive).
///
/// Layout, so load_gltf_scene() gives the scene back unchanged: one glTF mesh per
/// rebraid::Mesh (same order and name, one TRIANGLES primitive with float POSITION and
/// unsigned short or int indices), one node per instance with a column-major `matrix` holding
/// the instance's transform, all nodes roots of scene 0 in instance order. Positions, indices
/// and transforms are stored exactly (floats are written with enough digits to round-trip).
///
/// With GltfWriteSettings::gpu_instancing, every run of two or more consecutive instances of
/// one mesh whose transforms are rotation times scale plus translation (no shear) becomes a
/// single node with EXT_mesh_gpu_instancing (float TRANSLATION, ROTATION, SCALE, listed as
/// required); the loader then gives the same instances in the same order, their transforms
/// rounded once through the float T, R, S (within a few float ulps of each column's length).
///
/// Throws rebraid::Error naming the path when the scene is invalid (Scene::validate()), has no
/// instances or a mesh without triangles (glTF cannot express these), the extension is neither
/// .glb nor .gltf, the buffer exceeds glTF's 4 GiB, or the file cannot be written.
void write_gltf_scene(const Scene& scene, const std::string& path,
                      const GltfWriteSettings& settings = {});

}  // namespace rebraid
