#pragma once

#include <cstdint>
#include <limits>
#include <span>

#include "rebraid/bbox.h"
#include "rebraid/build_prim.h"
#include "rebraid/build_settings.h"

namespace rebraid {

/// Bounds, centroid bounds and total weight of a range of BuildPrims.
struct RangeInfo {
    BBox3f bounds;
    BBox3f centroid_bounds;
    std::uint64_t weight = 0;
    std::uint32_t count = 0;

    void add(const BuildPrim& prim) {
        bounds.extend(prim.bounds);
        centroid_bounds.extend(prim.centroid());
        weight += prim.weight;
        ++count;
    }
    void merge(const RangeInfo& other) {
        bounds.extend(other.bounds);
        centroid_bounds.extend(other.centroid_bounds);
        weight += other.weight;
        count += other.count;
    }
};

/// Parallel above `parallel_threshold` prims; min/max and integer sums make the result
/// independent of how the work was divided.
RangeInfo compute_range_info(std::span<const BuildPrim> prims, std::size_t parallel_threshold);

/// The best object split found by SAH binning over centroids (Wald and Havran 2006), with
/// each bin counting the weights of its prims (re-braiding paper §4.3).
struct BinnedSplit {
    int axis = -1;              ///< -1: no split separates the centroids
    std::uint32_t bin = 0;      ///< prims in bins [0, bin) go left
    float origin = 0.0f;        ///< centroid coordinate of bin 0's lower edge
    float scale = 0.0f;         ///< bins per unit length along `axis`
    std::uint32_t bin_count = 0;
    float cost = std::numeric_limits<float>::infinity();  ///< A_L W_L + A_R W_R (half areas)

    bool is_valid() const { return axis >= 0; }
    std::uint32_t bin_of(const BuildPrim& prim) const;
    bool goes_left(const BuildPrim& prim) const { return bin_of(prim) < bin; }
};

BinnedSplit find_binned_split(std::span<const BuildPrim> prims, const RangeInfo& info,
                              const BuildSettings& settings);

}  // namespace rebraid
