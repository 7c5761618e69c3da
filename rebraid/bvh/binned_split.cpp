#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/exact_split.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "rebraid/bvh/build_box.h"
#include "rebraid/bvh/parallel_partition.h"
#include "rebraid/core/parallel_blocks.h"

namespace rebraid {
namespace {

constexpr std::uint32_t kMaxBins = 256;

/// Maps centroids to bins on all three axes at once, with the operations of
/// BinnedSplit::bin_of (see there), so binning and partitioning always agree.
struct BinMapping {
#if defined(__AVX__)
    __m128 twice_origin, half_scale, last_bin;

    BinMapping(Vec3f origin, Vec3f scale, std::uint32_t bin_count)
        : twice_origin(
              _mm_setr_ps(origin.x + origin.x, origin.y + origin.y, origin.z + origin.z, 0.0f)),
          half_scale(_mm_setr_ps(scale.x * 0.5f, scale.y * 0.5f, scale.z * 0.5f, 0.0f)),
          last_bin(_mm_set1_ps(float(bin_count - 1))) {}

    void bins_of(const BuildBox& box, std::int32_t out[4]) const {
        __m128 position = _mm_mul_ps(_mm_sub_ps(box.twice_centre(), twice_origin), half_scale);
        // max(p, 0) then min(p, last): the operand order of bin_of's comparisons.
        position = _mm_min_ps(_mm_max_ps(position, _mm_setzero_ps()), last_bin);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(position));
    }
#else
    Vec3f origin, scale;
    float last_bin;

    BinMapping(Vec3f origin3, Vec3f scale3, std::uint32_t bin_count)
        : origin(origin3), scale(scale3), last_bin(float(bin_count - 1)) {}

    void bins_of(const BuildBox& box, std::int32_t out[4]) const {
        const Vec3f c2 = box.twice_centre();
        for (int a = 0; a < 3; ++a) {
            float position = (c2[a] - (origin[a] + origin[a])) * (scale[a] * 0.5f);
            position = position > 0.0f ? position : 0.0f;
            position = position < last_bin ? position : last_bin;
            out[a] = std::int32_t(position);
        }
    }
#endif
};

/// No prim count: a bin is empty exactly when its box is, and one store fewer per update
/// counts (binning is bound by stores).
struct Bin {
    BuildBox bounds;
    std::uint64_t weight;
};

/// Per-axis bins of one range (or one block of it), stored axis after axis with a stride of
/// bin_count, so small ranges clear and sweep only the bins they use.
class BinView {
public:
    BinView(Bin* storage, std::uint32_t bin_count) : bins_(storage), bin_count_(bin_count) {}

    void clear() {
        for (std::uint32_t i = 0; i < 3 * bin_count_; ++i) bins_[i] = {BuildBox::empty(), 0};
    }
    Bin* axis(int a) const { return bins_ + std::size_t(a) * bin_count_; }

    void add(const BuildPrim& prim, const BinMapping& mapping) {
        const BuildBox box = BuildBox::of(prim);
        std::int32_t index[4];
        mapping.bins_of(box, index);
        for (int a = 0; a < 3; ++a) {
            Bin& bin = bins_[std::size_t(a) * bin_count_ + std::uint32_t(index[a])];
            bin.bounds.extend(box);
            bin.weight += prim.weight;
        }
    }
    void add(std::span<const BuildPrim> prims, const BinMapping& mapping) {
        for (const BuildPrim& prim : prims) add(prim, mapping);
    }
    /// Adds even-numbered prims here and odd ones to `other`. Neighbouring prims tend to
    /// fall into the same bins, and each bin update must wait for the previous one to reach
    /// memory; alternating two sets of bins halves those chains.
    void add_alternating(std::span<const BuildPrim> prims, const BinMapping& mapping,
                         BinView& other) {
        std::size_t i = 0;
        for (; i + 1 < prims.size(); i += 2) {
            add(prims[i], mapping);
            other.add(prims[i + 1], mapping);
        }
        if (i < prims.size()) add(prims[i], mapping);
    }
    void merge(const BinView& other) {
        for (std::uint32_t i = 0; i < 3 * bin_count_; ++i) {
            bins_[i].bounds.extend(other.bins_[i].bounds);
            bins_[i].weight += other.bins_[i].weight;
        }
    }

private:
    Bin* bins_;
    std::uint32_t bin_count_;
};

/// Parallel binning gives each block its own bins; larger ranges use larger blocks than
/// kParallelBlock so that there are at most this many sets of bins to clear and merge.
constexpr std::size_t kMaxBinBlocks = 32;

/// Bins for the default bin count live on the stack; only larger counts allocate.
constexpr std::uint32_t kStackBins = 32;
/// Ranges of at least this many prims bin alternately into two sets of bins.
constexpr std::size_t kAlternateBinsMin = 128;

/// Storage for one set of bins: on the stack for up to kStackBins bins per axis.
class BinStorage {
public:
    explicit BinStorage(std::uint32_t bin_count) : bin_count_(bin_count) {
        if (bin_count > kStackBins) heap_.resize(3 * std::size_t(bin_count));
    }
    BinView view() { return {heap_.empty() ? stack_.data() : heap_.data(), bin_count_}; }

private:
    std::array<Bin, 3 * kStackBins> stack_;
    std::vector<Bin> heap_;
    std::uint32_t bin_count_;
};

/// Adds `prims` to `bins` (already cleared), serially.
void bin_serially(std::span<const BuildPrim> prims, const BinMapping& mapping, BinView bins,
                  std::uint32_t bin_count) {
    if (prims.size() < kAlternateBinsMin) {
        bins.add(prims, mapping);
        return;
    }
    BinStorage odd_storage(bin_count);
    BinView odd = odd_storage.view();
    odd.clear();
    bins.add_alternating(prims, mapping, odd);
    bins.merge(odd);
}

/// Fills `bins` (already cleared) with `prims`; in parallel blocks at or above `threshold`.
/// Min/max and integer sums are exact, so the result does not depend on the blocks.
void fill_bins(std::span<const BuildPrim> prims, const BinMapping& mapping, BinView bins,
               std::uint32_t bin_count, std::size_t threshold) {
    if (prims.size() < threshold) {
        bin_serially(prims, mapping, bins, bin_count);
        return;
    }
    const std::size_t block_count = std::min(kMaxBinBlocks, parallel_block_count(prims.size()));
    const std::size_t block_size = (prims.size() + block_count - 1) / block_count;
    std::vector<Bin> storage(block_count * 3 * bin_count);
    tbb::parallel_for(std::size_t(0), block_count, [&](std::size_t b) {
        BinView block_bins(storage.data() + b * 3 * bin_count, bin_count);
        block_bins.clear();
        const std::size_t begin = b * block_size;
        const std::size_t end = std::min(prims.size(), begin + block_size);
        bin_serially(prims.subspan(begin, end - begin), mapping, block_bins, bin_count);
    });
    for (std::size_t b = 0; b < block_count; ++b)
        bins.merge(BinView(storage.data() + b * 3 * bin_count, bin_count));
}

/// Sweeps each axis's bins: right-to-left suffix costs, then left to right. Ties keep the
/// first (lowest axis, lowest bin) candidate, so the choice is reproducible. A side whose
/// box is empty holds no prim, and such cuts are skipped.
BinnedSplit sweep_bins(const BinView& bins, std::uint32_t bin_count, Vec3f scale) {
    constexpr float kNoPrims = -1.0f;  // right_cost of an empty suffix (real costs are >= 0)
    std::array<float, kMaxBins> right_cost;
    // The best cut in locals rather than in the returned struct, which lives in memory.
    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1;
    std::uint32_t best_bin = 0;
    for (int a = 0; a < 3; ++a) {
        if (!(scale[a] > 0.0f)) continue;
        const Bin* axis_bins = bins.axis(a);
        BuildBox right = BuildBox::empty();
        std::uint64_t weight = 0;
        for (std::uint32_t b = bin_count - 1; b > 0; --b) {
            right.extend(axis_bins[b].bounds);
            weight += axis_bins[b].weight;
            right_cost[b] =
                right.is_empty() ? kNoPrims : right.half_area() * weight_as_float(weight);
        }
        BuildBox left = BuildBox::empty();
        weight = 0;
        for (std::uint32_t b = 1; b < bin_count; ++b) {
            left.extend(axis_bins[b - 1].bounds);
            weight += axis_bins[b - 1].weight;
            if (right_cost[b] == kNoPrims || left.is_empty()) continue;
            const float cost = left.half_area() * weight_as_float(weight) + right_cost[b];
            if (cost < best_cost) {
                best_cost = cost;
                best_axis = a;
                best_bin = b;
            }
        }
    }
    BinnedSplit best;
    best.axis = best_axis;
    best.bin = best_bin;
    best.cost = best_cost;
    return best;
}

/// BinnedSplit::goes_left for a fixed axis, simplified without changing any result:
/// uint(clamp(p, 0, last)) < bin, for 1 <= bin <= last, holds exactly when !(p >= bin)
/// (NaN included, which bin_of sends to bin 0). Same position arithmetic as bin_of.
template <int kAxis>
struct GoesLeft {
    float twice_origin, half_scale, bin;

    bool operator()(const BuildPrim& prim) const {
        const float twice_centre = prim.bounds.min[kAxis] + prim.bounds.max[kAxis];
        return !((twice_centre - twice_origin) * half_scale >= bin);
    }
};

/// BinnedSplit::goes_left of an exact split, for a fixed axis.
template <int kAxis>
struct GoesBelow {
    float twice_centre_below;

    bool operator()(const BuildPrim& prim) const {
        return prim.bounds.min[kAxis] + prim.bounds.max[kAxis] < twice_centre_below;
    }
};

SplitResult to_split_result(const PartitionResult<RangeAccumulator>& partition) {
    return {std::uint32_t(partition.left_count), partition.left.to_info(),
            partition.right.to_info()};
}

/// Calls partition(goes_left) with the predicate instantiated for split's axis, so the hot
/// loop reads its coordinate directly.
template <class Partition>
SplitResult with_axis_predicate(const BinnedSplit& split, Partition partition) {
    if (split.is_exact()) {
        const float below = split.twice_centre_below;
        switch (split.axis) {
            case 0:
                return to_split_result(partition(GoesBelow<0>{below}));
            case 1:
                return to_split_result(partition(GoesBelow<1>{below}));
            default:
                return to_split_result(partition(GoesBelow<2>{below}));
        }
    }
    const float twice_origin = split.origin + split.origin, half_scale = split.scale * 0.5f;
    const float bin = float(split.bin);
    switch (split.axis) {
        case 0:
            return to_split_result(partition(GoesLeft<0>{twice_origin, half_scale, bin}));
        case 1:
            return to_split_result(partition(GoesLeft<1>{twice_origin, half_scale, bin}));
        default:
            return to_split_result(partition(GoesLeft<2>{twice_origin, half_scale, bin}));
    }
}

}  // namespace

RangeInfo compute_range_info(std::span<const BuildPrim> prims, std::size_t parallel_threshold) {
    auto accumulate = [&](std::size_t begin, std::size_t end, RangeAccumulator acc) {
        for (std::size_t i = begin; i != end; ++i) acc.add(prims[i]);
        return acc;
    };
    // Min/max and integer sums are exact, so any division of the work gives the same result.
    return reduce_over_blocks(prims.size(), parallel_threshold, RangeAccumulator{}, accumulate,
                              [](RangeAccumulator a, const RangeAccumulator& b) {
                                  a.merge(b);
                                  return a;
                              })
        .to_info();
}

BinnedSplit find_binned_split(std::span<const BuildPrim> prims, const RangeInfo& info,
                              const BuildSettings& settings) {
    if (prims.size() <= kMaxExactSplitPrims) return find_exact_split(prims);
    // Small ranges get fewer bins: clearing and sweeping them dominates their cost.
    const std::uint32_t bin_count =
        std::min({settings.bin_count, kMaxBins, std::max(info.count / settings.prims_per_bin, 4u)});
    const Vec3f extent = info.centroid_bounds.extent();
    // Bins slightly narrower than extent / bin_count so the largest centroid lands in the
    // last bin rather than one past it. Axes without extent get scale 0: all in bin 0.
    Vec3f scale;
    for (int a = 0; a < 3; ++a)
        scale[a] = extent[a] > 0.0f ? (float(bin_count) * 0.99999f) / extent[a] : 0.0f;
    const Vec3f origin = info.centroid_bounds.min;

    BinStorage storage(bin_count);
    BinView bins = storage.view();
    bins.clear();
    fill_bins(prims, BinMapping(origin, scale, bin_count), bins, bin_count,
              settings.parallel_threshold);

    BinnedSplit best = sweep_bins(bins, bin_count, scale);
    if (best.is_valid()) {
        best.origin = origin[best.axis];
        best.scale = scale[best.axis];
        best.bin_count = bin_count;
    }
    return best;
}

SplitResult apply_binned_split(std::span<BuildPrim> prims, const BinnedSplit& split,
                               std::span<BuildPrim> scratch, std::size_t parallel_threshold) {
    if (split.is_exact() && prims.size() <= kMaxExactSplitPrims)
        return apply_exact_split(prims, split);
    return with_axis_predicate(split, [&](auto goes_left) {
        return partition_summarized<RangeAccumulator>(prims, goes_left, parallel_threshold,
                                                      scratch);
    });
}

SplitResult apply_binned_split_into(std::span<const BuildPrim> prims, std::span<BuildPrim> out,
                                    const BinnedSplit& split, std::size_t parallel_threshold) {
    return with_axis_predicate(split, [&](auto goes_left) {
        return partition_summarized_into<RangeAccumulator>(prims, out, goes_left,
                                                           parallel_threshold);
    });
}

SplitResult apply_split_in_or_across(std::span<BuildPrim> prims, std::span<BuildPrim> other,
                                     const BinnedSplit& split, std::size_t parallel_threshold,
                                     bool& moved) {
    moved = !(split.is_exact() && prims.size() <= kMaxExactSplitPrims);
    if (!moved) return apply_exact_split(prims, split);
    return apply_binned_split_into(prims, other, split, parallel_threshold);
}

}  // namespace rebraid
