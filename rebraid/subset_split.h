#pragma once

#include <cstdint>
#include <limits>
#include <span>

#include "rebraid/binned_split.h"
#include "rebraid/build_prim.h"

namespace rebraid {

/// Most prims find_subset_split handles (it tries 2^(n-1) - 1 bipartitions).
inline constexpr std::uint32_t kMaxSubsetPrims = 6;

/// The best SAH split of a tiny range, found by trying every division into two non-empty
/// sets. Ranges this small are most of a top-down build's SAH evaluations (each candidate
/// leaf needs one to compare its cost with splitting), and trying at most 31 bipartitions
/// costs less than clearing and sweeping bins, while finding the optimal split.
struct SubsetSplit {
    std::uint32_t left_mask = 0;  ///< bit i set: prim i goes left; 0: no split
    float cost = std::numeric_limits<float>::infinity();  ///< A_L W_L + A_R W_R (half areas)

    bool is_valid() const { return left_mask != 0; }
};

/// Precondition: prims.size() <= kMaxSubsetPrims. Fewer than two prims, or only infinite or
/// NaN costs (overflowing coordinates), give no split. Ties keep the first bipartition in a
/// fixed order, so the result is reproducible.
SubsetSplit find_subset_split(std::span<const BuildPrim> prims);

/// Moves the left prims to the front (both sides keep their order) and measures both sides.
/// Precondition: split.is_valid(), found for these prims.
SplitResult apply_subset_split(std::span<BuildPrim> prims, const SubsetSplit& split);

}  // namespace rebraid
