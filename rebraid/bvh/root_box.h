#pragma once

#include <limits>
#include <vector>

#include "rebraid/bvh/wide_node.h"

namespace rebraid {

/// The box around every child of a BVH's root node, kept beside a structure so that a query
/// can reject a ray that misses it before preparing anything for the traversal
/// (root_box_cull.h). Where the root is a leaf there is no such node test to stand in for:
/// the box is then all of space, which no ray with a finite origin starts outside of.
struct RootBox {
    static constexpr float kInfinity = std::numeric_limits<float>::infinity();
    alignas(16) float lower[4] = {-kInfinity, -kInfinity, -kInfinity, -kInfinity};  ///< x, y, z
    alignas(16) float upper[4] = {kInfinity, kInfinity, kInfinity, kInfinity};
};

/// The root box of the BVH whose nodes are `nodes`, rooted at `root`: the union of the
/// root's child boxes, plane by plane, so that no ray the root's box test lets into a child
/// is rejected by the box (root_box_cull.h).
inline RootBox root_box_of(const std::vector<WideNode>& nodes, NodeRef root) {
    RootBox box;
    if (!root.is_inner()) return box;
    const BBox3f bounds = nodes[root.node_id()].bounds();
    if (bounds.is_empty()) return box;
    for (int a = 0; a < 3; ++a) {
        box.lower[a] = bounds.min[a];
        box.upper[a] = bounds.max[a];
    }
    return box;
}

}  // namespace rebraid
