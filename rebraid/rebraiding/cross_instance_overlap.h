#pragma once

#include <span>

#include "rebraid/bvh/build_prim.h"
#include "rebraid/rebraiding/bref.h"

namespace rebraid {

/// True when the boxes of two BRefs of `prims` that belong to different instances overlap:
/// their intersection has a positive surface area (boxes that only touch at an edge or a
/// corner do not count, coplanar flat boxes that share a region do).
///
/// Re-braiding exists to undo overlap between object BVHs (Benthin et al. 2017, §1, §4.2):
/// a segment where no two instances' boxes overlap has none to undo, and nor has any segment
/// below it, which holds a subset of its BRefs once it opens nothing. One sort along the
/// segment's largest axis and a sweep that stops at the first overlap found; O(n log n) for
/// boxes that overlap along that axis only in small groups.
bool has_cross_instance_overlap(std::span<const BuildPrim> prims,
                                std::span<const BRefTarget> targets);

}  // namespace rebraid
