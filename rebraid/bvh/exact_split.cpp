#include "rebraid/bvh/exact_split.h"

#include <array>
#include <bit>

#include "rebraid/bvh/build_box.h"
#include "rebraid/core/error.h"

namespace rebraid {

BinnedSplit find_exact_split(std::span<const BuildPrim> prims) {
    REBRAID_ASSERT(prims.size() <= kMaxExactSplitPrims);
    const auto n = std::uint32_t(prims.size());
    BinnedSplit best;
    if (n < 2) return best;
    std::array<BuildBox, kMaxExactSplitPrims> boxes, centres;  // centres: twice the centroid
    for (std::uint32_t i = 0; i < n; ++i) {
        boxes[i] = BuildBox::of(prims[i]);
        centres[i] = BuildBox::point(boxes[i].twice_centre());
    }
    // Every division into two non-empty sides once: masks over the first n - 1 prims, the
    // last prim always on the mask's right. A division counts when a plane separates the
    // sides' centroids; the side below the plane goes left. Ties keep the first division
    // and the lowest axis.
    float best_cost = std::numeric_limits<float>::infinity();
    const std::uint32_t mask_end = 1u << (n - 1);
    for (std::uint32_t mask = 1; mask < mask_end; ++mask) {
        BuildBox left = BuildBox::empty(), right = BuildBox::empty();
        BuildBox left_centres = BuildBox::empty(), right_centres = BuildBox::empty();
        std::uint64_t left_weight = 0, right_weight = 0;
        for (std::uint32_t i = 0; i < n; ++i) {
            if (mask & (1u << i)) {
                left.extend(boxes[i]);
                left_centres.extend(centres[i]);
                left_weight += prims[i].weight;
            } else {
                right.extend(boxes[i]);
                right_centres.extend(centres[i]);
                right_weight += prims[i].weight;
            }
        }
        const std::uint32_t left_below = left_centres.axes_below(right_centres);
        const std::uint32_t separating_axes = left_below | right_centres.axes_below(left_centres);
        if (separating_axes == 0) continue;
        const float cost = left.half_area() * weight_as_float(left_weight) +
                           right.half_area() * weight_as_float(right_weight);
        if (!(cost < best_cost)) continue;
        best_cost = cost;
        best.axis = std::countr_zero(separating_axes);
        // The plane lies at the lowest centroid of the side above it.
        const BuildBox& above = (left_below >> best.axis) & 1u ? right_centres : left_centres;
        best.twice_centre_below = above.to_bbox().min[best.axis];
    }
    best.bin_count = 0;
    best.cost = best_cost;
    return best;
}

SplitResult apply_exact_split(std::span<BuildPrim> prims, const BinnedSplit& split) {
    REBRAID_ASSERT(prims.size() <= kMaxExactSplitPrims && split.is_exact());
    const auto n = std::uint32_t(prims.size());
    std::array<BuildPrim, kMaxExactSplitPrims> original;
    std::copy(prims.begin(), prims.end(), original.begin());
    // The order of the general partition (partition_summarized_into): left prims forward
    // from the front, right ones backward from the back.
    RangeAccumulator left, right;
    std::uint32_t front = 0, back = n;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (split.goes_left(original[i])) {
            left.add(original[i]);
            prims[front++] = original[i];
        } else {
            right.add(original[i]);
            prims[--back] = original[i];
        }
    }
    return {front, left.to_info(), right.to_info()};
}

}  // namespace rebraid
