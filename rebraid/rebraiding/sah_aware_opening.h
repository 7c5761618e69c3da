#pragma once

#include <cstdint>
#include <span>

#include "rebraid/rebraiding/bref.h"
#include "rebraid/rebraiding/bref_opening.h"
#include "rebraid/rebraiding/rebraid_settings.h"

namespace rebraid {

/// Estimated SAH cost (in half-area units, as `rebraid stats` sums it) of one segment with
/// the BRefs `criterion` picks left closed and with them opened.
struct OpeningEstimate {
    double closed_cost = 0.0;
    double opened_cost = 0.0;
    std::uint32_t opened = 0;  ///< BRefs the opening would open (what fits the free space)

    bool lowers_sah() const { return opened > 0 && opened_cost < closed_cost; }
};

/// SAH-aware opening (beyond the paper): the paper opens every BRef its criterion picks (§4.2);
/// this estimates whether doing so lowers the segment's SAH, without writing anything.
///
/// The estimate has two parts, each the same for both sides except where opening changes it:
///  - the BRefs themselves, exactly: a closed BRef to an inner node costs its world box (the
///    entry node's visit) plus each child's test inside the instance over the child's mapped
///    box (a parallelepiped, what the object-space test accepts), times the child's triangle
///    count for a leaf; opened, each child costs its world AABB instead (times its triangle
///    count for a leaf), and the entry visit is gone. What lies below the children is
///    visited with the same probability either way and cancels. A leaf opened into its
///    triangles swaps its box times its count for the triangles' boxes. Each BRef also costs
///    `instance_entry_cost` times its box for the ray transform;
///  - the top-level nodes above them: the wide nodes a binned-SAH build over the BRef boxes
///    (weight 1 each) makes in its first `estimate_levels` levels, each costing its box's
///    area, and below those, per child, its area for each wide node its BRefs still need
///    ((count - 1) / (kBvhWidth - 1)). This is where overlap shows: BRefs of crossing
///    instances, opened, regroup into smaller boxes, while opening separated instances only
///    adds nodes.
/// `free_space`: what the segment may add; BRefs open in array order while it lasts, as in
/// open_brefs. `info` is compute_range_info of `prims` (the builder has it at hand). Large
/// segments bin in parallel, deterministically.
OpeningEstimate estimate_opening(std::span<const BuildPrim> prims, const RangeInfo& info,
                                 std::span<const BRefTarget> targets,
                                 const OpeningCriterion& criterion, const BRefSource& source,
                                 std::uint32_t free_space, const RebraidSettings& settings);

}  // namespace rebraid
