#pragma once

#include <span>
#include <vector>

#include "rebraid/bbox.h"
#include "rebraid/build_prim.h"
#include "rebraid/build_settings.h"
#include "rebraid/wide_node.h"

namespace rebraid {

/// The tree a wide-BVH build produces: nodes plus the root reference. Leaf references name
/// ranges of the BuildPrim array the build reordered.
struct WideBvh {
    std::vector<WideNode> nodes;
    NodeRef root = NodeRef::empty();  ///< empty for no prims; a leaf when one leaf suffices
    BBox3f bounds;
};

/// Top-down binned-SAH build of an 8-wide BVH: each node is grown by splitting its child
/// with the largest surface area until it has kBvhWidth children or no child is worth
/// splitting. Reorders `prims` into leaf order. Parallel (TBB) over subtrees and, for large
/// ranges, inside binning and partitioning; the tree is the same for any thread count.
WideBvh build_wide_bvh(std::span<BuildPrim> prims, const BuildSettings& settings);

}  // namespace rebraid
