#pragma once

// The glTF node forest as the animator needs it (internal to rebraid::io): parents, a
// parents-first order, rest poses and rest world transforms in double.

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "rebraid/io/gltf_animation_math.h"

namespace tinygltf {
class Model;
}

namespace rebraid::gltf_animation {

inline constexpr std::uint32_t kNoParent = std::numeric_limits<std::uint32_t>::max();

/// Every node of the document (not only the default scene's: skins may use others).
struct NodeHierarchy {
    std::vector<std::uint32_t> parent;  ///< kNoParent for roots
    std::vector<std::uint32_t> order;   ///< all nodes, each after its parent (depth-first)
    std::vector<NodeTrs> rest_trs;      ///< the node's TRS (identity parts where absent)
    std::vector<Affine3d> rest_local;   ///< `matrix`, or T * R * S
    std::vector<Affine3d> rest_world;   ///< product of rest_local from the root

    std::size_t node_count() const { return parent.size(); }
};

/// Reads the hierarchy. Throws rebraid::Error starting with `error_prefix` for a child index
/// out of range, a node with two parents, a cycle, or a malformed or non-finite
/// matrix / translation / rotation / scale.
NodeHierarchy read_node_hierarchy(const tinygltf::Model& model, const std::string& error_prefix);

/// The nodes whose world transform changes when the nodes flagged in `is_animated` move:
/// those nodes and all their descendants, parents first.
std::vector<std::uint32_t> nodes_below(const NodeHierarchy& hierarchy,
                                       const std::vector<bool>& is_animated);

}  // namespace rebraid::gltf_animation
