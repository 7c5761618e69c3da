#pragma once

#include <span>
#include <vector>

#include "rebraid/bvh/build_prim.h"
#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/wide_bvh.h"

namespace rebraid {

/// Top-down SAH build of an 8-wide BVH: each node is grown by splitting its child with the
/// largest surface area until it has kBvhWidth children or no child is worth splitting.
/// Splits are those of find_binned_split (binned, or exact for tiny ranges) applied in the
/// order of apply_binned_split, so builders using those get the same trees. Reorders `prims` into
/// leaf order. Parallel (TBB): subtrees of at least task_threshold prims are tasks, and ranges of
/// at least parallel_threshold prims bin and partition in parallel blocks. The tree depends
/// on the input and the settings only, never on the thread count or timing.
WideBvh build_wide_bvh(std::span<BuildPrim> prims, const BuildSettings& settings);

}  // namespace rebraid
