#pragma once

#include <cstdint>

#include "rebraid/bvh/build_prim.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/types.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// What a BRef points at: a node of the BVH of an instance's mesh. It is exactly what the BRef
/// becomes in the finished top level: a leaf item.
using BRefTarget = TopLevelItem;

/// A BRef (re-braiding paper §3.2): a reference to an object-BVH node with its world-space
/// bounds, its instance and its (estimated) primitive count. The builder stores each BRef in
/// two parts so that partitioning, which moves BRefs many times, moves only 32 bytes:
///  - a BuildPrim in the segmented BRef array: `bounds` = world bounds, `weight` = estimated
///    primitive count (what SAH binning reads, §4.3), `id` = the slot of the rest;
///  - a BRefTarget in a second array that never moves: node and instance.
struct BRef {
    BuildPrim prim;
    BRefTarget target;
};

/// Segment of the BRef array (§5.2): BRefs in [start, end), free space for opened children
/// in [end, end_extra). The segment also owns the BRefTarget slots
/// [next_target, next_target + free space): every child BRef opening creates takes one array
/// slot and one target slot, so both run out together.
struct BRefSegment {
    std::uint32_t start = 0;
    std::uint32_t end = 0;
    std::uint32_t end_extra = 0;
    std::uint32_t next_target = 0;
    /// False once the termination rules (§4.4) stopped opening for this subtree.
    bool can_open = true;
    /// SAH estimates in a row, from this segment's ancestors down, that found opening would
    /// not pay (RebraidSettings::estimate_give_up).
    std::uint32_t failed_estimates = 0;

    std::uint32_t size() const { return end - start; }
    std::uint32_t free_space() const { return end_extra - end; }
};

}  // namespace rebraid
