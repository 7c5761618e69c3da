#pragma once

// glTF morph targets (internal to rebraid::io): POSITION deltas of one Mesh and the
// weighted sum that morphs a vertex. Other target attributes (NORMAL, TANGENT) are ignored:
// the scene model holds positions only.

#include <cstddef>
#include <string>
#include <vector>

#include "rebraid/core/types.h"
#include "rebraid/io/gltf_scene.h"

namespace tinygltf {
class Model;
}

namespace rebraid::gltf_animation {

/// Number of morph targets of glTF mesh `mesh_id` over its loaded primitives `ranges` (0 when
/// it has none). Throws rebraid::Error starting with `error_prefix` when the primitives
/// disagree (the specification requires the same count on every primitive) or when the
/// mesh's default `weights` do not have one weight per target.
std::size_t morph_target_count(const tinygltf::Model& model, std::size_t mesh_id,
                               const std::vector<GltfPrimitiveRange>& ranges,
                               const std::string& error_prefix);

/// POSITION deltas of every target for every vertex of one Mesh, and the mesh's default
/// weights.
struct MorphTargets {
    std::size_t target_count = 0;
    std::vector<Vec3f> deltas;           ///< vertex * target_count + target; 0 where absent
    std::vector<float> default_weights;  ///< the glTF mesh's `weights`, else zeros
};

/// Reads the targets of glTF mesh `mesh_id` lined up with the Mesh's `vertex_count`
/// positions. Throws rebraid::Error starting with `error_prefix` for a target POSITION
/// accessor whose count is not its primitive's vertex count, or of the wrong type.
MorphTargets read_morph_targets(const tinygltf::Model& model, std::size_t mesh_id,
                                const std::vector<GltfPrimitiveRange>& ranges,
                                std::size_t vertex_count, const std::string& error_prefix);

/// base + sum_t weights[t] * deltas[t] for one vertex (`deltas` = its target_count deltas).
inline Vec3f morph_vertex(Vec3f base, const Vec3f* deltas, const float* weights,
                          std::size_t target_count) {
    for (std::size_t t = 0; t < target_count; ++t)
        if (weights[t] != 0.0f) base = base + weights[t] * deltas[t];
    return base;
}

}  // namespace rebraid::gltf_animation
