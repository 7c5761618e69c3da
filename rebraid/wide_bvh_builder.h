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

/// Top-down SAH build of an 8-wide BVH: each node is grown by splitting its child with the
/// largest surface area until it has kBvhWidth children or no child is worth splitting.
/// Splits are those of find_binned_split (binned, or exact for tiny ranges) applied in the
/// order of apply_binned_split, so builders using those get the same trees. Reorders `prims` into
/// leaf order. Parallel (TBB): subtrees of at least task_threshold prims are tasks, and ranges of
/// at least parallel_threshold prims bin and partition in parallel blocks. The tree depends
/// on the input and the settings only, never on the thread count or timing.
WideBvh build_wide_bvh(std::span<BuildPrim> prims, const BuildSettings& settings);

}  // namespace rebraid
