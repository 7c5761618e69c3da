#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/build_prim.h"

#if defined(__AVX__)
#include <immintrin.h>
#endif

namespace rebraid {

// BuildBox::of reads a BuildPrim's six bound floats with two 4-float loads.
static_assert(sizeof(BuildPrim) == 32 && offsetof(BuildPrim, bounds) == 0 &&
              sizeof(BBox3f) == 6 * sizeof(float));

/// A box for the builders' hot loops (binning, partitioning, sweeps; builder internals only).
/// With AVX it is one 8-float register holding {min.xyz, -, -max.xyz, -}: storing the upper
/// corner negated makes extending a box a single min instruction, and a bin update one load
/// and one store, which matters because binning is bound by stores. Without AVX a plain
/// BBox3f stands in (the portable path).
struct BuildBox {
#if defined(__AVX__)
    // No member initialisers: bins are arrays of these, initialised only as far as used.
    __m256 lanes;

    static BuildBox empty() {
        return {_mm256_set1_ps(std::numeric_limits<float>::infinity())};
    }
    /// Loads {min.x, min.y, min.z, max.x} and {min.z, max.x, max.y, max.z} rotated to
    /// {max.x, max.y, max.z, min.z}: the unused lanes then hold coordinates, never the id or
    /// weight, whose bit patterns are denormal floats that could slow the arithmetic.
    static BuildBox of(const BuildPrim& prim) {
        const float* p = &prim.bounds.min.x;
        const __m128 tail = _mm_loadu_ps(p + 2);
        const __m128 upper = _mm_shuffle_ps(tail, tail, _MM_SHUFFLE(0, 3, 2, 1));
        return {_mm256_set_m128(negate(upper), _mm_loadu_ps(p))};
    }
    /// The box holding only `point`.
    static BuildBox point(__m128 point) {
        return {_mm256_set_m128(negate(point), point)};
    }
    void extend(const BuildBox& b) {
        lanes = _mm256_min_ps(lanes, b.lanes);
    }
    __m128 lower() const {
        return _mm256_castps256_ps128(lanes);
    }
    __m128 negated_upper() const {
        return _mm256_extractf128_ps(lanes, 1);
    }
    /// min + max per axis (exactly: a - (-b) == a + b): twice the centre, without a multiply
    /// that a compiler could fuse into a following subtraction, so bin mappings round
    /// identically everywhere.
    __m128 twice_centre() const {
        return _mm_sub_ps(lower(), negated_upper());
    }
    __m128 centre() const {
        return _mm_mul_ps(twice_centre(), _mm_set1_ps(0.5f));
    }
    void extend_point(__m128 point) {
        lanes = _mm256_min_ps(lanes, _mm256_set_m128(negate(point), point));
    }
    /// min - max per axis, the negated extent: its pairwise products are the extent's.
    __m128 negated_extent() const {
        return _mm_add_ps(lower(), negated_upper());
    }
    /// Same products and sums, in the same order, as BBox3f::half_area (non-empty box).
    float half_area() const {
        const __m128 d = negated_extent();
        const __m128 d_yzx = _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 0, 2, 1));
        const __m128 products = _mm_mul_ps(d, d_yzx);  // xy, yz, zx
        const __m128 sum = _mm_add_ss(products, _mm_shuffle_ps(products, products, 1));
        return _mm_cvtss_f32(_mm_add_ss(sum, _mm_movehl_ps(products, products)));
    }
    /// True unless the box holds at least one point (min.x <= max.x).
    bool is_empty() const {
        return !(_mm_cvtss_f32(negated_extent()) <= 0.0f);
    }
    /// True when min > max along any axis (is_empty looks at x alone, enough for boxes
    /// that only ever grow; a box cut down by another can come out empty along y or z).
    bool is_empty_on_any_axis() const {
        return (_mm_movemask_ps(_mm_cmpgt_ps(negated_extent(), _mm_setzero_ps())) & 7) != 0;
    }
    /// Bit a set when this box lies entirely below `other` along axis a (max < other's min).
    std::uint32_t axes_below(const BuildBox& other) const {
        const __m128 below = _mm_cmplt_ps(negate(negated_upper()), other.lower());
        return std::uint32_t(_mm_movemask_ps(below)) & 7u;
    }
    BBox3f to_bbox() const {
        alignas(32) float v[8];
        _mm256_store_ps(v, lanes);
        return {{v[0], v[1], v[2]}, {-v[4], -v[5], -v[6]}};
    }

private:
    static __m128 negate(__m128 v) {
        return _mm_xor_ps(v, _mm_set1_ps(-0.0f));
    }
#else
    BBox3f box;

    static BuildBox empty() {
        return {};
    }
    static BuildBox of(const BuildPrim& prim) {
        return {prim.bounds};
    }
    static BuildBox point(Vec3f point) {
        return {{point, point}};
    }
    void extend(const BuildBox& b) {
        box.extend(b.box);
    }
    Vec3f twice_centre() const {
        return box.min + box.max;
    }
    Vec3f centre() const {
        return box.center();
    }
    void extend_point(Vec3f point) {
        box.extend(point);
    }
    float half_area() const {
        return box.half_area();
    }
    bool is_empty() const {
        return !(box.min.x <= box.max.x);
    }
    bool is_empty_on_any_axis() const {
        return box.is_empty();
    }
    std::uint32_t axes_below(const BuildBox& other) const {
        std::uint32_t axes = 0;
        for (int a = 0; a < 3; ++a) axes |= std::uint32_t(box.max[a] < other.box.min[a]) << a;
        return axes;
    }
    BBox3f to_bbox() const {
        return box;
    }
#endif
};

/// RangeInfo accumulated with BuildBox arithmetic: what compute_range_info and the
/// partitions sum up per block or side. Merging is exact (min/max, integer sums).
struct RangeAccumulator {
    BuildBox bounds = BuildBox::empty(), centroids = BuildBox::empty();
    std::uint64_t weight = 0;
    std::uint32_t count = 0;

    void add(const BuildPrim& prim) {
        const BuildBox box = BuildBox::of(prim);
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

/// A weight as a float for SAH costs: through int64, which converts with one instruction
/// (uint64 needs a branchy sequence before AVX-512). Weights stay far below 2^63.
inline float weight_as_float(std::uint64_t weight) {
    return float(std::int64_t(weight));
}

}  // namespace rebraid
