#include "rebraid/binned_split.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <limits>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace rebraid {
namespace {

constexpr std::uint32_t kMaxBins = 256;
constexpr float kInf = std::numeric_limits<float>::infinity();

std::uint32_t bin_index(float centroid, float origin, float scale, std::uint32_t bin_count) {
    const float position = (centroid - origin) * scale;
    // Clamp in float first: a huge value must not overflow the integer conversion.
    return std::uint32_t(std::clamp(position, 0.0f, float(bin_count - 1)));
}

/// A box as two 4-float vectors (lane 3 unused), so the hot loops below extend boxes with
/// two vector instructions. BuildPrim is laid out {min.xyz, max.xyz, id, weight}: unaligned
/// 4-float loads at min.x and max.x pick up a neighbour in lane 3, which no result reads.
struct Box4 {
#if defined(__SSE2__)
    // No member initialisers: bins are arrays of these, initialised only as far as used.
    __m128 lower, upper;

    static Box4 empty() { return {_mm_set1_ps(kInf), _mm_set1_ps(-kInf)}; }

    static Box4 of(const BuildPrim& prim) {
        const float* p = &prim.bounds.min.x;
        return {_mm_loadu_ps(p), _mm_loadu_ps(p + 3)};
    }
    void extend(const Box4& b) {
        lower = _mm_min_ps(lower, b.lower);
        upper = _mm_max_ps(upper, b.upper);
    }
    void extend_point(const Box4& b) {  // extends by b's centroid
        const __m128 c = _mm_mul_ps(_mm_add_ps(b.lower, b.upper), _mm_set1_ps(0.5f));
        lower = _mm_min_ps(lower, c);
        upper = _mm_max_ps(upper, c);
    }
    /// Bin of b's centroid on each axis (lanes 0..2).
    static void bins_of(const Box4& b, __m128 origin, __m128 scale, __m128 last_bin,
                        std::int32_t out[4]) {
        const __m128 c = _mm_mul_ps(_mm_add_ps(b.lower, b.upper), _mm_set1_ps(0.5f));
        __m128 position = _mm_mul_ps(_mm_sub_ps(c, origin), scale);
        position = _mm_min_ps(_mm_max_ps(position, _mm_setzero_ps()), last_bin);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(position));
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
    void extend_point(const Box4& b) { box.extend(b.box.center()); }
    BBox3f to_bbox() const { return box; }
#endif
};

struct Bin {
    Box4 bounds;
    std::uint32_t count;
    std::uint64_t weight;
};

/// Per-axis bins of one range. Only the first bin_count bins of each axis are initialised:
/// small ranges, the vast majority, must not pay for clearing all kMaxBins.
struct Bins {
    std::array<std::array<Bin, kMaxBins>, 3> axes;
    std::uint32_t bin_count;

    explicit Bins(std::uint32_t count) : bin_count(count) {
        for (auto& axis : axes)
            for (std::uint32_t b = 0; b < count; ++b) axis[b] = {Box4::empty(), 0, 0};
    }

    void merge(const Bins& other) {
        for (int a = 0; a < 3; ++a)
            for (std::uint32_t b = 0; b < bin_count; ++b) {
                Bin& bin = axes[a][b];
                const Bin& add = other.axes[a][b];
                bin.bounds.extend(add.bounds);
                bin.count += add.count;
                bin.weight += add.weight;
            }
    }
};

struct RangeAccumulator {
    Box4 bounds = Box4::empty(), centroids = Box4::empty();
    std::uint64_t weight = 0;
    std::uint32_t count = 0;

    void merge(const RangeAccumulator& other) {
        bounds.extend(other.bounds);
        centroids.extend(other.centroids);
        weight += other.weight;
        count += other.count;
    }
    RangeInfo to_info() const { return {bounds.to_bbox(), centroids.to_bbox(), weight, count}; }
};

}  // namespace

std::uint32_t BinnedSplit::bin_of(const BuildPrim& prim) const {
    return bin_index(prim.centroid()[axis], origin, scale, bin_count);
}

RangeInfo compute_range_info(std::span<const BuildPrim> prims, std::size_t parallel_threshold) {
    auto accumulate = [&](const tbb::blocked_range<std::size_t>& r, RangeAccumulator acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const Box4 box = Box4::of(prims[i]);
            acc.bounds.extend(box);
            acc.centroids.extend_point(box);
            acc.weight += prims[i].weight;
        }
        acc.count += std::uint32_t(r.size());
        return acc;
    };
    // Min/max and integer sums are exact, so any division of the work gives the same result.
    if (prims.size() < parallel_threshold)
        return accumulate({0, prims.size()}, RangeAccumulator{}).to_info();
    return tbb::parallel_reduce(
               tbb::blocked_range<std::size_t>(0, prims.size(), 4096), RangeAccumulator{},
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

    auto fill = [&](const tbb::blocked_range<std::size_t>& r, Bins& bins) {
#if defined(__SSE2__)
        const __m128 origin4 = _mm_setr_ps(origin.x, origin.y, origin.z, 0.0f);
        const __m128 scale4 = _mm_setr_ps(scale.x, scale.y, scale.z, 0.0f);
        const __m128 last_bin = _mm_set1_ps(float(bin_count - 1));
#endif
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const Box4 box = Box4::of(prims[i]);
            std::int32_t index[4];
#if defined(__SSE2__)
            Box4::bins_of(box, origin4, scale4, last_bin, index);
#else
            const Vec3f c = prims[i].centroid();
            for (int a = 0; a < 3; ++a)
                index[a] = std::int32_t(bin_index(c[a], origin[a], scale[a], bin_count));
#endif
            for (int a = 0; a < 3; ++a) {
                Bin& bin = bins.axes[a][index[a]];
                bin.bounds.extend(box);
                ++bin.count;
                bin.weight += prims[i].weight;
            }
        }
    };
    Bins bins(bin_count);
    if (prims.size() < settings.parallel_threshold) {
        fill({0, prims.size()}, bins);
    } else {
        bins = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, prims.size(), 4096), bins,
            [&](const tbb::blocked_range<std::size_t>& r, Bins partial) {
                fill(r, partial);
                return partial;
            },
            [](Bins a, const Bins& b) {
                a.merge(b);
                return a;
            });
    }

    // Sweep each axis: right-to-left suffix areas, then left to right. Ties keep the first
    // (lowest axis, lowest bin) candidate, so the choice is reproducible.
    BinnedSplit best;
    std::array<float, kMaxBins> right_cost;
    std::array<std::uint32_t, kMaxBins> right_count;
    for (int a = 0; a < 3; ++a) {
        if (scale[a] <= 0.0f) continue;
        const auto& axis_bins = bins.axes[a];
        Box4 right = Box4::empty();
        std::uint64_t weight = 0;
        std::uint32_t count = 0;
        for (std::uint32_t b = bin_count - 1; b > 0; --b) {
            right.extend(axis_bins[b].bounds);
            weight += axis_bins[b].weight;
            count += axis_bins[b].count;
            right_cost[b] = right.to_bbox().half_area() * float(weight);
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
            const float cost = left.to_bbox().half_area() * float(weight) + right_cost[b];
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

}  // namespace rebraid
