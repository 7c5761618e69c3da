#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/transform.h"
#include "rebraid/rebraiding/bref.h"
#include "rebraid/rebraiding/bref_bounds.h"
#include "rebraid/rebraiding/bref_children.h"

namespace rebraid {

/// Paper §4.2: in a segment, find the axis of largest extent of the segment's bounds; a BRef
/// is worth opening when it refers to an inner node (a leaf has nothing to open into) and its
/// extent along that axis exceeds `open_threshold` times the segment's. With `open_leaves`, leaves
/// of several triangles count as openable too. Other rules narrow the choice further with
/// `selected`: one flag per BRef of the segment (index from the segment's start); only
/// flagged BRefs are opened.
struct OpeningCriterion {
    int axis = 0;
    float min_extent = 0.0f;
    bool open_leaves = false;
    std::span<const std::uint8_t> selected;

    OpeningCriterion(const BBox3f& segment_bounds, float open_threshold, bool open_leaves = false);
    /// `index`: the BRef's position from the segment's start (read only with `selected`).
    bool wants_to_open(const BuildPrim& prim, const BRefTarget& target,
                       std::size_t index = 0) const {
        return is_openable(target.object_node, open_leaves) &&
               prim.bounds.extent()[axis] > min_extent && (selected.empty() || selected[index]);
    }
};

/// What the builder learns from one pass over a segment before opening it: how many BRefs
/// meet the criterion (§5.2 splits the free space by these counts; none means nothing can
/// open) and whether they all belong to one instance (the first termination rule of §4.4).
/// One pass instead of three.
struct OpeningScan {
    std::uint32_t openable = 0;
    bool is_single_instance = true;  ///< also true for no BRefs
};

/// The scan of `prims` under `criterion` (whose `selected` must be empty); parallel at or
/// above `parallel_threshold` prims, with a result independent of the division.
OpeningScan scan_for_opening(std::span<const BuildPrim> prims, std::span<const BRefTarget> targets,
                             const OpeningCriterion& criterion, std::size_t parallel_threshold);

/// Paper §5.3: opens the BRefs of `segment` that meet `criterion`, in array order, while the
/// segment's free space lasts (a BRef opens iff the children wanted by it and all BRefs before
/// it fit, so serial and parallel runs open exactly the same ones). The first child replaces
/// the parent; its siblings are appended at the segment's end, each taking the next target
/// slot. A child's bounds are its object box mapped to world space (conservative AABB, §5.4);
/// its primitive count is the parent's divided by the number of children, or the real count
/// when `source` has exact counts. Updates
/// `segment.end` and `segment.next_target`; returns how many BRefs were opened. Large
/// segments are processed in parallel blocks whose output slots come from prefix sums;
/// smaller ones in one serial pass without allocating. When BRefs were opened and
/// `resulting_info` is given, it receives the segment's range info after the opening
/// (what compute_range_info would return), which saves the builder a pass.
std::uint32_t open_brefs(BRefSegment& segment, std::span<BuildPrim> prims,
                         std::span<BRefTarget> targets, const OpeningCriterion& criterion,
                         const BRefSource& source, std::size_t parallel_threshold,
                         RangeInfo* resulting_info = nullptr);

/// The BRefs open_brefs opens among `prims` (a segment's, from its start) under `criterion`
/// with `free_space` slots for extra children, as indices into `prims` in array order: those
/// the criterion picks while their children fit; the first that does not fit leaves it and
/// every later one closed. For estimates that must open what open_brefs would.
std::vector<std::uint32_t> brefs_to_open(std::span<const BuildPrim> prims,
                                         std::span<const BRefTarget> targets,
                                         const OpeningCriterion& criterion,
                                         const BRefSource& source, std::uint32_t free_space);

}  // namespace rebraid
