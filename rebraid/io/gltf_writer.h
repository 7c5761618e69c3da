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
/// rebraid::Mesh with triangles (same order and name, one TRIANGLES primitive with float
/// POSITION and unsigned short or int indices), one node per instance with a column-major
/// `matrix` holding the instance's transform (hidden instances below), all nodes roots of
/// scene 0 in instance order. Positions, indices
/// and transforms are stored exactly (floats are written with enough digits to round-trip).
///
/// With GltfWriteSettings::gpu_instancing, every run of two or more consecutive instances of
/// one mesh whose transforms are rotation times scale plus translation (no shear) becomes a
/// single node with EXT_mesh_gpu_instancing (float TRANSLATION, ROTATION, SCALE, listed as
/// required); the loader then gives the same instances in the same order, their transforms
/// rounded once through the float T, R, S (within a few float ulps of each column's length).
///
/// Hidden instances (README "Conventions"): an instance of a mesh without triangles (as the
/// loader places a hidden instance) or with a singular transform (|determinant| < 1e-30) is
/// never hit, and is written as exporters hide an object: a node with scale 0 (its own mesh,
/// or the first written mesh for a mesh without triangles), or, joining a run of any mesh, an
/// EXT_mesh_gpu_instancing element with SCALE 0. Meshes without triangles are not written
/// (glTF cannot store them); the loader gives every hidden instance its number back, as an
/// identity instance of its empty hidden mesh appended after the written meshes. So a loaded
/// scene, whose only mesh without triangles is that last hidden mesh, round-trips with the
/// same MeshIds too.
///
/// Throws rebraid::Error naming the path when the scene is invalid (Scene::validate(), singular
/// transforms allowed), has no instances, no mesh with triangles or a mesh without triangles
/// that no instance uses (glTF cannot express these), the extension is neither .glb nor
/// .gltf, the buffer exceeds glTF's 4 GiB, or the file cannot be written.
void write_gltf_scene(const Scene& scene, const std::string& path,
                      const GltfWriteSettings& settings = {});

}  // namespace rebraid
