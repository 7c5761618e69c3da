#include "rebraid/subset_split.h"

#include <array>
#include <bit>

#include "rebraid/build_box.h"
#include "rebraid/error.h"

namespace rebraid {

SubsetSplit find_subset_split(std::span<const BuildPrim> prims) {
    REBRAID_ASSERT(prims.size() <= kMaxSubsetPrims);
    const auto n = std::uint32_t(prims.size());
    SubsetSplit best;
    if (n < 2) return best;
    std::array<BuildBox, kMaxSubsetPrims> boxes;
    for (std::uint32_t i = 0; i < n; ++i) boxes[i] = BuildBox::of(prims[i]);
    // Masks over the first n - 1 prims; the last prim always goes right, so each division
    // is tried once (not also as its mirror image).
    const std::uint32_t mask_end = 1u << (n - 1);
    for (std::uint32_t mask = 1; mask < mask_end; ++mask) {
        BuildBox left = BuildBox::empty(), right = BuildBox::empty();
        std::uint64_t left_weight = 0, right_weight = 0;
        for (std::uint32_t i = 0; i < n; ++i) {
            if (mask & (1u << i)) {
                left.extend(boxes[i]);
                left_weight += prims[i].weight;
            } else {
                right.extend(boxes[i]);
                right_weight += prims[i].weight;
            }
        }
        const float cost = left.half_area() * weight_as_float(left_weight) +
                           right.half_area() * weight_as_float(right_weight);
        if (cost < best.cost) {
            best.left_mask = mask;
            best.cost = cost;
        }
    }
    return best;
}

SplitResult apply_subset_split(std::span<BuildPrim> prims, const SubsetSplit& split) {
    const auto n = std::uint32_t(prims.size());
    std::array<BuildPrim, kMaxSubsetPrims> original;
    for (std::uint32_t i = 0; i < n; ++i) original[i] = prims[i];
    const auto left_count = std::uint32_t(std::popcount(split.left_mask));
    std::uint32_t left = 0, right = left_count;
    RangeAccumulator left_info, right_info;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (split.left_mask & (1u << i)) {
            left_info.add(original[i]);
            prims[left++] = original[i];
        } else {
            right_info.add(original[i]);
            prims[right++] = original[i];
        }
    }
    return {left_count, left_info.to_info(), right_info.to_info()};
}

}  // namespace rebraid
