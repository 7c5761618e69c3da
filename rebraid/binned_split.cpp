#include "rebraid/binned_split.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "rebraid/parallel_partition.h"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace rebraid {
namespace {

constexpr std::uint32_t kMaxBins = 256;
constexpr float kInf = std::numeric_limits<float>::infinity();

// Box4::of reads a BuildPrim's six bound floats with two 4-float loads.
static_assert(sizeof(BuildPrim) == 32 && offsetof(BuildPrim, bounds) == 0 &&
              sizeof(BBox3f) == 6 * sizeof(float));

/// A box as two 4-float vectors (lane 3 unused), so the hot loops below extend boxes with
/// two vector instructions.
struct Box4 {
#if defined(__SSE2__)
    // No member initialisers: bins are arrays of these, initialised only as far as used.
    __m128 lower, upper;

    static Box4 empty() { return {_mm_set1_ps(kInf), _mm_set1_ps(-kInf)}; }

    /// Loads {min.x, min.y, min.z, max.x} and {min.z, max.x, max.y, max.z} rotated to
    /// {max.x, max.y, max.z, min.z}: lane 3 then holds coordinates, never the id or weight,
    /// whose bit patterns are denormal floats that could slow the arithmetic below.
    static Box4 of(const BuildPrim& prim) {
        const float* p = &prim.bounds.min.x;
        const __m128 tail = _mm_loadu_ps(p + 2);
        return {_mm_loadu_ps(p), _mm_shuffle_ps(tail, tail, _MM_SHUFFLE(0, 3, 2, 1))};
    }
    void extend(const Box4& b) {
        lower = _mm_min_ps(lower, b.lower);
        upper = _mm_max_ps(upper, b.upper);
    }
    __m128 centre() const { return _mm_mul_ps(_mm_add_ps(lower, upper), _mm_set1_ps(0.5f)); }
    void extend_point(__m128 point) {
        lower = _mm_min_ps(lower, point);
        upper = _mm_max_ps(upper, point);
    }
    /// Same operations, in the same order, as BBox3f::half_area (for a non-empty box).
    float half_area() const {
        const __m128 d = _mm_sub_ps(upper, lower);
        const __m128 d_yzx = _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 0, 2, 1));
        const __m128 products = _mm_mul_ps(d, d_yzx);  // xy, yz, zx
        const __m128 sum = _mm_add_ss(products, _mm_shuffle_ps(products, products, 1));
        return _mm_cvtss_f32(_mm_add_ss(sum, _mm_movehl_ps(products, products)));
    }
    BBox3f to_bbox() const {
        alignas(16) float lo[4], hi[4];
        _mm_store_ps(lo, lower);
        _mm_store_ps(hi, upper);
        return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    }
#else
    BBox3f box;

    static Box4 empty() { return {}; }
    static Box4 of(const BuildPrim& prim) { return {prim.bounds}; }
    void extend(const Box4& b) { box.extend(b.box); }
    Vec3f centre() const { return box.center(); }
    void extend_point(Vec3f point) { box.extend(point); }
    float half_area() const { return box.half_area(); }
    BBox3f to_bbox() const { return box; }
#endif
};

/// Maps centroids to bins on all three axes at once, with the operations of
/// BinnedSplit::bin_of (see there), so binning and partitioning always agree.
struct BinMapping {
#if defined(__SSE2__)
    __m128 origin, scale, last_bin;

    BinMapping(Vec3f origin3, Vec3f scale3, std::uint32_t bin_count)
        : origin(_mm_setr_ps(origin3.x, origin3.y, origin3.z, 0.0f)),
          scale(_mm_setr_ps(scale3.x, scale3.y, scale3.z, 0.0f)),
          last_bin(_mm_set1_ps(float(bin_count - 1))) {}

    void bins_of(const Box4& box, std::int32_t out[4]) const {
        __m128 position = _mm_mul_ps(_mm_sub_ps(box.centre(), origin), scale);
        // max(p, 0) then min(p, last): the operand order of bin_of's comparisons.
        position = _mm_min_ps(_mm_max_ps(position, _mm_setzero_ps()), last_bin);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(position));
    }
#else
    Vec3f origin, scale;
    float last_bin;

    BinMapping(Vec3f origin3, Vec3f scale3, std::uint32_t bin_count)
        : origin(origin3), scale(scale3), last_bin(float(bin_count - 1)) {}

    void bins_of(const Box4& box, std::int32_t out[4]) const {
        const Vec3f c = box.centre();
        for (int a = 0; a < 3; ++a) {
            float position = (c[a] - origin[a]) * scale[a];
            position = position > 0.0f ? position : 0.0f;
            position = position < last_bin ? position : last_bin;
            out[a] = std::int32_t(position);
        }
    }
#endif
};

struct Bin {
    Box4 bounds;
    std::uint64_t weight;
    std::uint32_t count;
};

/// Per-axis bins of one range (or one block of it), stored axis after axis with a stride of
/// bin_count, so small ranges clear and sweep only the bins they use.
class BinView {
public:
    BinView(Bin* storage, std::uint32_t bin_count) : bins_(storage), bin_count_(bin_count) {}

    void clear() {
        for (std::uint32_t i = 0; i < 3 * bin_count_; ++i) bins_[i] = {Box4::empty(), 0, 0};
    }
    Bin* axis(int a) const { return bins_ + std::size_t(a) * bin_count_; }

    void add(std::span<const BuildPrim> prims, const BinMapping& mapping) {
        Bin* x = axis(0);
        Bin* y = axis(1);
        Bin* z = axis(2);
        for (const BuildPrim& prim : prims) {
            const Box4 box = Box4::of(prim);
            std::int32_t index[4];
            mapping.bins_of(box, index);
            add_to(x[index[0]], box, prim.weight);
            add_to(y[index[1]], box, prim.weight);
            add_to(z[index[2]], box, prim.weight);
        }
    }
    void merge(const BinView& other) {
        for (std::uint32_t i = 0; i < 3 * bin_count_; ++i) {
            bins_[i].bounds.extend(other.bins_[i].bounds);
            bins_[i].weight += other.bins_[i].weight;
            bins_[i].count += other.bins_[i].count;
        }
    }

private:
    static void add_to(Bin& bin, const Box4& box, std::uint32_t weight) {
        bin.bounds.extend(box);
        bin.weight += weight;
        ++bin.count;
    }

    Bin* bins_;
    std::uint32_t bin_count_;
};

/// RangeInfo accumulated with Box4 arithmetic; also the per-side summary of
/// apply_binned_split's partition.
struct RangeAccumulator {
    Box4 bounds = Box4::empty(), centroids = Box4::empty();
    std::uint64_t weight = 0;
    std::uint32_t count = 0;

    void add(const BuildPrim& prim) {
        const Box4 box = Box4::of(prim);
        bounds.extend(box);
        centroids.extend_point(box.centre());
        weight += prim.weight;
        ++count;
    }
    void merge(const RangeAccumulator& other) {
        bounds.extend(other.bounds);
        centroids.extend(other.centroids);
        weight += other.weight;
        count += other.count;
    }
    RangeInfo to_info() const { return {bounds.to_bbox(), centroids.to_bbox(), weight, count}; }
};

/// Prims per block of the parallel loops (fixed, so blocks never depend on thread count).
constexpr std::size_t kBlock = 4096;
/// Parallel binning gives each block its own bins; larger ranges use larger blocks so that
/// there are at most this many sets of bins to clear and merge.
constexpr std::size_t kMaxBinBlocks = 32;

/// Fills `bins` (already cleared) with `prims`; in parallel blocks at or above `threshold`.
/// Min/max and integer sums are exact, so the result does not depend on the blocks.
void fill_bins(std::span<const BuildPrim> prims, const BinMapping& mapping, BinView bins,
               std::uint32_t bin_count, std::size_t threshold) {
    if (prims.size() < threshold) {
        bins.add(prims, mapping);
        return;
    }
    const std::size_t block_count =
        std::min(kMaxBinBlocks, (prims.size() + kBlock - 1) / kBlock);
    const std::size_t block_size = (prims.size() + block_count - 1) / block_count;
    std::vector<Bin> storage(block_count * 3 * bin_count);
    tbb::parallel_for(std::size_t(0), block_count, [&](std::size_t b) {
        BinView block_bins(storage.data() + b * 3 * bin_count, bin_count);
        block_bins.clear();
        const std::size_t begin = b * block_size;
        const std::size_t end = std::min(prims.size(), begin + block_size);
        block_bins.add(prims.subspan(begin, end - begin), mapping);
    });
    for (std::size_t b = 0; b < block_count; ++b)
        bins.merge(BinView(storage.data() + b * 3 * bin_count, bin_count));
}

}  // namespace

RangeInfo compute_range_info(std::span<const BuildPrim> prims, std::size_t parallel_threshold) {
    auto accumulate = [&](const tbb::blocked_range<std::size_t>& r, RangeAccumulator acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) acc.add(prims[i]);
        return acc;
    };
    // Min/max and integer sums are exact, so any division of the work gives the same result.
    if (prims.size() < parallel_threshold)
        return accumulate({0, prims.size()}, RangeAccumulator{}).to_info();
    return tbb::parallel_reduce(
               tbb::blocked_range<std::size_t>(0, prims.size(), kBlock), RangeAccumulator{},
               accumulate,
               [](RangeAccumulator a, const RangeAccumulator& b) {
                   a.merge(b);
                   return a;
               })
        .to_info();
}

BinnedSplit find_binned_split(std::span<const BuildPrim> prims, const RangeInfo& info,
                              const BuildSettings& settings) {
    // Small ranges need no more bins than prims (fewer bins to clear and sweep).
    const std::uint32_t bin_count =
        std::min({settings.bin_count, kMaxBins, std::max(info.count, 4u)});
    const Vec3f extent = info.centroid_bounds.extent();
    // Bins slightly narrower than extent / bin_count so the largest centroid lands in the
    // last bin rather than one past it. Axes without extent get scale 0: all in bin 0.
    Vec3f scale;
    for (int a = 0; a < 3; ++a)
        scale[a] = extent[a] > 0.0f ? (float(bin_count) * 0.99999f) / extent[a] : 0.0f;
    const Vec3f origin = info.centroid_bounds.min;

    std::array<Bin, 3 * kMaxBins> storage;  // only the first 3 * bin_count are used
    BinView bins(storage.data(), bin_count);
    bins.clear();
    fill_bins(prims, BinMapping(origin, scale, bin_count), bins, bin_count,
              settings.parallel_threshold);

    // Sweep each axis: right-to-left suffix costs, then left to right. Ties keep the first
    // (lowest axis, lowest bin) candidate, so the choice is reproducible.
    BinnedSplit best;
    std::array<float, kMaxBins> right_cost;
    std::array<std::uint32_t, kMaxBins> right_count;
    for (int a = 0; a < 3; ++a) {
        if (scale[a] <= 0.0f) continue;
        const Bin* axis_bins = bins.axis(a);
        Box4 right = Box4::empty();
        std::uint64_t weight = 0;
        std::uint32_t count = 0;
        for (std::uint32_t b = bin_count - 1; b > 0; --b) {
            right.extend(axis_bins[b].bounds);
            weight += axis_bins[b].weight;
            count += axis_bins[b].count;
            // Empty suffixes (count 0) have an undefined area; they are skipped below.
            right_cost[b] = count > 0 ? right.half_area() * float(weight) : 0.0f;
            right_count[b] = count;
        }
        Box4 left = Box4::empty();
        weight = 0;
        count = 0;
        for (std::uint32_t b = 1; b < bin_count; ++b) {
            left.extend(axis_bins[b - 1].bounds);
            weight += axis_bins[b - 1].weight;
            count += axis_bins[b - 1].count;
            if (count == 0 || right_count[b] == 0) continue;
            const float cost = left.half_area() * float(weight) + right_cost[b];
            if (cost < best.cost) {
                best.axis = a;
                best.bin = b;
                best.cost = cost;
            }
        }
    }
    if (best.is_valid()) {
        best.origin = origin[best.axis];
        best.scale = scale[best.axis];
        best.bin_count = bin_count;
    }
    return best;
}

SplitResult apply_binned_split(std::span<BuildPrim> prims, const BinnedSplit& split,
                               std::span<BuildPrim> scratch, std::size_t parallel_threshold) {
    const auto partition = partition_summarized<RangeAccumulator>(
        prims, [&split](const BuildPrim& prim) { return split.goes_left(prim); },
        parallel_threshold, scratch);
    return {std::uint32_t(partition.left_count), partition.left.to_info(),
            partition.right.to_info()};
}

}  // namespace rebraid
