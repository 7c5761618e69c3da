#pragma once

// glTF skins (internal to rebraid::io): joints with inverse bind matrices, per-vertex joint
// influences (JOINTS_n / WEIGHTS_n), and linear blend skinning of one vertex.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "rebraid/core/transform.h"
#include "rebraid/io/gltf_animation_math.h"
#include "rebraid/io/gltf_scene.h"

namespace tinygltf {
class Model;
}

namespace rebraid::gltf_animation {

/// A glTF skin: its joint nodes and their inverse bind matrices (identity when the skin has
/// none, as the specification says).
struct Skin {
    std::vector<std::uint32_t> joints;
    std::vector<Affine3d> inverse_bind_matrices;  ///< one per joint
};

/// Reads skin `skin_id`. Throws rebraid::Error starting with `error_prefix` for a missing
/// skin, a joint that is not a node, or inverse bind matrices that are not float MAT4 or
/// fewer than the joints.
Skin read_skin(const tinygltf::Model& model, int skin_id, const std::string& error_prefix);

/// Joint id of influences whose vertex has no weight at all: such vertices follow the
/// skinned node's own world transform (they keep their rest placement).
inline constexpr std::uint32_t kUnweightedJoint = std::numeric_limits<std::uint32_t>::max();

/// Joint influences of every vertex of one Mesh: `influence_count` (joint, weight) pairs per
/// vertex (4 per JOINTS_n / WEIGHTS_n set), weights scaled to sum 1.
struct SkinInfluences {
    std::size_t influence_count = 0;
    std::vector<std::uint32_t> joints;       ///< vertex * influence_count + i; skin joint index
    std::vector<float> weights;              ///< same layout; 0 for unused pairs
    std::uint32_t required_joint_count = 0;  ///< 1 + the largest joint with a non-zero weight
};

/// Reads JOINTS_n / WEIGHTS_n of the loaded primitives `ranges` of glTF mesh `mesh_id`, lined
/// up with the Mesh's `vertex_count` positions. Throws rebraid::Error starting with
/// `error_prefix` for a primitive without JOINTS_0 / WEIGHTS_0, accessors whose count is not
/// the primitive's vertex count, or of the wrong type.
SkinInfluences read_skin_influences(const tinygltf::Model& model, std::size_t mesh_id,
                                    const std::vector<GltfPrimitiveRange>& ranges,
                                    std::size_t vertex_count, const std::string& error_prefix);

/// Linear blend skinning of `position` with the influences of one vertex:
/// (sum_i weight_i * joint_matrix[joint_i]) * position.
inline Vec3f skin_vertex(Vec3f position, const std::uint32_t* joints, const float* weights,
                         std::size_t influence_count, const AffineTransform* joint_matrices,
                         const AffineTransform& unweighted) {
    if (joints[0] == kUnweightedJoint) return unweighted.transform_point(position);
    Vec3f result{0, 0, 0};
    for (std::size_t i = 0; i < influence_count; ++i) {
        if (weights[i] == 0.0f) continue;
        result = result + weights[i] * joint_matrices[joints[i]].transform_point(position);
    }
    return result;
}

}  // namespace rebraid::gltf_animation
