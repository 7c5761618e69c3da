#pragma once

#include <cstdint>
#include <limits>
#include <span>

#include "rebraid/bvh/build_prim.h"
#include "rebraid/bvh/build_settings.h"
#include "rebraid/core/bbox.h"

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

/// Ranges of at most this many prims are split exactly rather than by binning (see
/// find_binned_split).
inline constexpr std::uint32_t kMaxExactSplitPrims = 4;

/// The best object split found by SAH binning over centroids (Wald and Havran 2006), with
/// each bin counting the weights of its prims (re-braiding paper §4.3); for small ranges an
/// exact split, which sends left the prims whose centroid lies below a plane.
struct BinnedSplit {
    int axis = -1;                ///< -1: no split separates the centroids
    std::uint32_t bin = 0;        ///< prims in bins [0, bin) go left
    float origin = 0.0f;          ///< centroid coordinate of bin 0's lower edge
    float scale = 0.0f;           ///< bins per unit length along `axis`
    std::uint32_t bin_count = 0;  ///< 0 for an exact split
    /// Exact splits only: prims whose min + max (twice the centroid) along `axis` is below
    /// this go left: the very sums the search compared, with no rounding step of their own.
    float twice_centre_below = 0.0f;
    float cost = std::numeric_limits<float>::infinity();  ///< A_L W_L + A_R W_R (half areas)

    bool is_valid() const { return axis >= 0; }
    bool is_exact() const { return bin_count == 0; }
    /// The bin the binning put `prim` in (binned splits only). Inline, and computed with
    /// exactly the operations of the SIMD binning, so partitions agree with the counts the
    /// split was chosen by and no side comes out empty: ((min + max) - 2 origin) * (scale /
    /// 2), clamped the way max/min instructions clamp (NaN goes to bin 0). No product feeds a
    /// sum, so a compiler that fuses multiply-adds cannot round one path differently.
    std::uint32_t bin_of(const BuildPrim& prim) const {
        const float twice_centre = prim.bounds.min[axis] + prim.bounds.max[axis];
        float position = (twice_centre - (origin + origin)) * (scale * 0.5f);
        position = position > 0.0f ? position : 0.0f;
        const float last = float(bin_count - 1);
        position = position < last ? position : last;
        return std::uint32_t(position);
    }
    bool goes_left(const BuildPrim& prim) const {
        if (is_exact()) return prim.bounds.min[axis] + prim.bounds.max[axis] < twice_centre_below;
        return bin_of(prim) < bin;
    }
};

/// The SAH split of a range: binned, or for at most kMaxExactSplitPrims prims exact (every
/// division of the prims by an axis-aligned plane between their centroids is tried, which
/// finds splits at least as good as bins and costs less than clearing and sweeping them;
/// ranges that small are most of a build's split searches). Ties go to the first candidate
/// in a fixed order, so the result is reproducible.
BinnedSplit find_binned_split(std::span<const BuildPrim> prims, const RangeInfo& info,
                              const BuildSettings& settings);

/// How apply_binned_split divided a range: prims [0, left_count) went left.
struct SplitResult {
    std::uint32_t left_count = 0;
    RangeInfo left, right;
};

/// Moves the prims `split` sends left to the front of `prims` and measures both sides while
/// they are in cache (what compute_range_info would return for each), saving a pass per
/// child. Through `scratch` (at least prims.size() elements, contents ignored; may be empty
/// below `parallel_threshold`, then a temporary is used), in parallel blocks at or above the
/// threshold. The order is the same as apply_binned_split_into's, and depends only on the
/// input and the threshold, never on the thread count. Precondition: split.is_valid().
SplitResult apply_binned_split(std::span<BuildPrim> prims, const BinnedSplit& split,
                               std::span<BuildPrim> scratch, std::size_t parallel_threshold);

/// apply_binned_split without the copy back: partitions `prims` into `out` (same size,
/// distinct memory), left prims first. Builders that alternate between two buffers save a
/// pass over the data per split. In parallel blocks at or above `parallel_threshold` prims
/// (a stable partition), serially below (right side reversed); never dependent on the
/// thread count. Precondition: split.is_valid().
SplitResult apply_binned_split_into(std::span<const BuildPrim> prims, std::span<BuildPrim> out,
                                    const BinnedSplit& split, std::size_t parallel_threshold);

/// A split of `prims` for a builder that alternates two buffers: the tiny ranges of exact splits
/// divided in place (switching buffers buys them nothing), the others partitioned into `other`
/// (same size, distinct memory; no copying back), measuring both sides on the way. Sets
/// `moved` to whether the prims now live in `other`. Precondition: split.is_valid().
SplitResult apply_split_in_or_across(std::span<BuildPrim> prims, std::span<BuildPrim> other,
                                     const BinnedSplit& split, std::size_t parallel_threshold,
                                     bool& moved);

}  // namespace rebraid
