#pragma once

#include <span>

#include "rebraid/bvh/wide_node.h"

namespace rebraid {

/// Sets every slot box of the tree below `root` that points at an inner node to the union of
/// that node's own slot boxes (post-order, so from the leaves up); leaf slots keep their
/// boxes. For builders whose children can end up with boxes their parent's slot was not made
/// from: a re-braiding build opens BRefs below a node after the node's box was written, and
/// the opened children's bounds, rounded on their own, may reach a few ulps past it. After
/// this pass every slot box holds everything below it. Returns the union of the root's
/// slots (empty for a leaf or empty root). Recursion depth is bounded by kMaxBvhDepth.
BBox3f fit_inner_boxes(std::span<WideNode> nodes, NodeRef root);

}  // namespace rebraid
