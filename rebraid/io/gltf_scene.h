#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rebraid/core/scene.h"

namespace tinygltf {
class Model;
}

namespace rebraid {

/// Limits and switches of the glTF loader. The limits guard against memory bombs: a file whose
/// (valid-looking) accessors would make the loader allocate more than this is rejected with a
/// rebraid::Error before the memory is taken.
struct GltfLoadOptions {
    /// Maximum triangles over all glTF meshes (each mesh counted once, not per instance).
    std::uint64_t max_triangles = 1'000'000'000;
    /// Maximum vertex positions over all glTF meshes (a POSITION accessor shared by several
    /// primitives counts once per primitive, as the loader copies it per primitive).
    std::uint64_t max_vertices = 1'000'000'000;
    /// Maximum instances (EXT_mesh_gpu_instancing lets a few bytes stand for one).
    std::uint64_t max_instances = 200'000'000;
    /// Keep the parsed glTF document in GltfLoadResult::model, for readers of what the scene
    /// model leaves out (animations, skins, morph targets, cameras, materials, texture
    /// coordinates). Off by default: it holds a copy of every buffer.
    bool keep_model = false;
};

/// Where one glTF primitive's geometry went in its Mesh: vertices
/// [first_vertex, first_vertex + vertex_count) are the primitive's POSITION elements in
/// accessor order (so any other per-vertex accessor of the primitive lines up with them), and
/// triangles [first_triangle, first_triangle + triangle_count) are its triangles.
struct GltfPrimitiveRange {
    std::uint32_t gltf_primitive = 0;  ///< index in the glTF mesh's `primitives`
    std::uint64_t first_vertex = 0;
    std::uint64_t vertex_count = 0;
    std::uint64_t first_triangle = 0;
    std::uint64_t triangle_count = 0;
    int material = -1;  ///< glTF material index, -1 for none
};

/// GltfLoadReport::instance_gpu_elements of an instance of a node without
/// EXT_mesh_gpu_instancing.
inline constexpr std::uint32_t kNotGpuInstanced = 0xFFFFFFFFu;
/// GltfLoadReport::hidden_mesh of a scene without hidden instances.
inline constexpr std::uint32_t kNoHiddenMesh = 0xFFFFFFFFu;

/// What the loader saw besides the scene: useful for tools that explain a file and for the
/// animation loader, which needs to know which glTF node each instance came from.
struct GltfLoadReport {
    /// Primitives per glTF topology mode (index = `mode`, 0 POINTS ... 6 TRIANGLE_FAN), over all
    /// meshes. Modes 0-3 are skipped by the loader; 4-6 become triangles.
    std::array<std::uint64_t, 7> primitive_count_by_mode{};
    /// glTF node index of every instance, in instance order (Scene::instances[i] came from node
    /// instance_node_ids[i]).
    std::vector<std::uint32_t> instance_node_ids;
    /// Per instance, its element in its node's EXT_mesh_gpu_instancing accessors, or
    /// kNotGpuInstanced for a node without the extension.
    std::vector<std::uint32_t> instance_gpu_elements;
    /// Instances whose transform is singular (|determinant| < 1e-30, e.g. a zero scale,
    /// which exporters use to hide objects), ascending. Each keeps its number but is placed
    /// as an identity instance of hidden_mesh, which has no triangles: it is never hit.
    std::vector<std::uint32_t> hidden_instances;
    /// The empty Mesh of hidden instances, appended after the file's meshes; kNoHiddenMesh
    /// when no instance is hidden.
    std::uint32_t hidden_mesh = kNoHiddenMesh;
    /// Per Mesh (index = MeshId = glTF mesh index), its loaded primitives in order (points
    /// and lines, which are skipped, have no entry).
    std::vector<std::vector<GltfPrimitiveRange>> mesh_primitives;
    /// Index of the glTF scene that was loaded (the default scene).
    std::uint32_t scene_id = 0;
    /// Instances whose node has a skin (loaded in the rest pose, skin ignored).
    std::uint64_t skinned_instance_count = 0;
    /// Primitives with morph targets (loaded with the base positions, targets ignored).
    std::uint64_t morphed_primitive_count = 0;

    /// Primitives of modes POINTS, LINES, LINE_LOOP and LINE_STRIP, which the loader skipped.
    std::uint64_t skipped_primitive_count() const {
        return primitive_count_by_mode[0] + primitive_count_by_mode[1] +
               primitive_count_by_mode[2] + primitive_count_by_mode[3];
    }
};

/// A loaded scene together with the loader's report.
struct GltfLoadResult {
    Scene scene;
    GltfLoadReport report;
    /// The parsed document when GltfLoadOptions::keep_model is set, else null. Accessors in
    /// it passed the loader's checks only where the loader read them: read others through
    /// resolve_gltf_accessor() (rebraid/io/gltf_accessor.h).
    std::shared_ptr<const tinygltf::Model> model;
};

/// Loads a .gltf or .glb file into a Scene following the project's conventions (README "Scene
/// conventions").
Scene load_gltf_scene(const std::string& path, const GltfLoadOptions& options = {});

/// As load_gltf_scene(), and also returns what the loader saw (see GltfLoadReport).
/// Throws rebraid::Error naming the file and the problem for any bad input.
GltfLoadResult load_gltf_scene_with_report(const std::string& path,
                                           const GltfLoadOptions& options = {});

}  // namespace rebraid
