#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>

#include "rebraid/bvh/hit_triangle.h"
#include "rebraid/core/simd_config.h"
#include "rebraid/core/triangle.h"
#include "rebraid/core/triangle_test.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// Most triangles one call of the group tests handles (one AVX2 register of lanes).
inline constexpr std::uint32_t kTriangleGroupSize = 8;

/// The closest hit of a group test: which triangle of the group, and its t, u, v.
struct TriangleGroupHit {
    std::uint32_t index = 0;
    float t = 0.0f, u = 0.0f, v = 0.0f;
};

#ifdef REBRAID_SIMD_AVX2

/// A ray's origin and direction broadcast to all lanes, made once per traversal.
struct TriangleGroupRay {
    __m256 org[3];
    __m256 dir[3];

    TriangleGroupRay(Vec3f origin, Vec3f direction) {
        for (int a = 0; a < 3; ++a) {
            org[a] = _mm256_set1_ps(origin[a]);
            dir[a] = _mm256_set1_ps(direction[a]);
        }
    }
};

namespace triangle_group_detail {

/// A vector of 3 components, one triangle per lane.
struct Vec3x8 {
    __m256 x, y, z;
};

inline Vec3x8 operator-(const Vec3x8& a, const Vec3x8& b) {
    return {_mm256_sub_ps(a.x, b.x), _mm256_sub_ps(a.y, b.y), _mm256_sub_ps(a.z, b.z)};
}
inline Vec3x8 operator+(const Vec3x8& a, const Vec3x8& b) {
    return {_mm256_add_ps(a.x, b.x), _mm256_add_ps(a.y, b.y), _mm256_add_ps(a.z, b.z)};
}
inline Vec3x8 cross(const Vec3x8& a, const Vec3x8& b) {
    return {_mm256_fmsub_ps(a.y, b.z, _mm256_mul_ps(a.z, b.y)),
            _mm256_fmsub_ps(a.z, b.x, _mm256_mul_ps(a.x, b.z)),
            _mm256_fmsub_ps(a.x, b.y, _mm256_mul_ps(a.y, b.x))};
}
inline __m256 dot(const Vec3x8& a, const __m256 (&b)[3]) {
    return _mm256_fmadd_ps(a.x, b[0], _mm256_fmadd_ps(a.y, b[1], _mm256_mul_ps(a.z, b[2])));
}
inline __m256 dot(const Vec3x8& a, const Vec3x8& b) {
    return _mm256_fmadd_ps(a.x, b.x, _mm256_fmadd_ps(a.y, b.y, _mm256_mul_ps(a.z, b.z)));
}

/// The corners of up to 8 triangles turned from the array-of-structures storage into one
/// lane per triangle; `triangle_of(i)` names lane i's triangle (i < count). Lane i holds
/// triangle min(i, count - 1): surplus lanes repeat the last triangle (no read past the
/// group) and are masked off by the caller; for groups of at most four (the common case),
/// lanes 4..7 are zero and only half the rows are loaded.
/// Each 16-byte row load takes a corner's x, y, z plus a neighbouring float; corner 2 is read
/// starting one float early (v1.z) so no load runs past the triangle's 36 bytes.
struct GroupCorners {
    static_assert(sizeof(TriangleVerts) == 36, "rows are read at fixed float offsets");
    Vec3x8 corner[3];

    /// From pre-arranged rows (row 3c + a: axis a of corner c, one triangle per lane).
    explicit GroupCorners(const __m256 (&rows)[9]) {
        for (int c = 0; c < 3; ++c) corner[c] = {rows[3 * c], rows[3 * c + 1], rows[3 * c + 2]};
    }

    template <class TriangleOfLane>
    GroupCorners(TriangleOfLane&& triangle_of, std::uint32_t count) {
        const float* row[kTriangleGroupSize];
        for (std::uint32_t i = 0; i < kTriangleGroupSize; ++i)
            row[i] = &triangle_of(std::min(i, count - 1))->v0.x;
        const bool is_half = count <= 4;
        // Rows of lane pairs (j, j + 4) share a register: a 4x4 transpose per 128-bit half
        // then yields lanes in order 0..7.
        const auto rows = [&](int j, int offset) {
            const __m128 low = _mm_loadu_ps(row[j] + offset);
            if (is_half) return _mm256_zextps128_ps256(low);
            return _mm256_insertf128_ps(_mm256_castps128_ps256(low),
                                        _mm_loadu_ps(row[j + 4] + offset), 1);
        };
        for (int c = 0; c < 3; ++c) {
            const int offset = c == 2 ? 5 : 3 * c;
            const __m256 r0 = rows(0, offset), r1 = rows(1, offset);
            const __m256 r2 = rows(2, offset), r3 = rows(3, offset);
            const __m256 lo01 = _mm256_unpacklo_ps(r0, r1), lo23 = _mm256_unpacklo_ps(r2, r3);
            const __m256 hi01 = _mm256_unpackhi_ps(r0, r1), hi23 = _mm256_unpackhi_ps(r2, r3);
            if (c < 2) {  // x, y, z = elements 0, 1, 2 of each row
                corner[c] = {_mm256_shuffle_ps(lo01, lo23, 0x44),
                             _mm256_shuffle_ps(lo01, lo23, 0xee),
                             _mm256_shuffle_ps(hi01, hi23, 0x44)};
            } else {  // x, y, z = elements 1, 2, 3
                corner[c] = {_mm256_shuffle_ps(lo01, lo23, 0xee),
                             _mm256_shuffle_ps(hi01, hi23, 0x44),
                             _mm256_shuffle_ps(hi01, hi23, 0xee)};
            }
        }
    }
};

/// The group test of the triangle test `kTest`: `mask` holds the lanes (bits) whose triangle
/// the ray hits with tnear <= t <= tfar, and w1, w2, sum, t per lane give the hit
/// (u = w1 / sum, v = w2 / sum).
template <TriangleTest kTest>
struct GroupTest;

/// The watertight test: the same arithmetic as intersect_triangle(), eight at a time (with
/// fused multiply-adds, which keep the exact negation of shared edges' functions).
template <>
struct GroupTest<TriangleTest::watertight> {
    unsigned mask = 0;
    __m256 w1, w2, sum, t;

    GroupTest(const GroupCorners& corners, std::uint32_t count, const TriangleGroupRay& ray,
              float tnear, float tfar) {
        const Vec3x8 org{ray.org[0], ray.org[1], ray.org[2]};
        const Vec3x8 a = corners.corner[0] - org;
        const Vec3x8 b = corners.corner[1] - org;
        const Vec3x8 c = corners.corner[2] - org;
        // Edge functions in Plücker form, see intersect_triangle().
        const __m256 w0 = dot(cross(b - c, b + c), ray.dir);
        w1 = dot(cross(c - a, c + a), ray.dir);
        w2 = dot(cross(a - b, a + b), ray.dir);
        const __m256 zero = _mm256_setzero_ps();
        sum = _mm256_add_ps(w0, _mm256_add_ps(w1, w2));
        // tolerance = kEdgeTolerance * |sum| (clearing the sign bit is the absolute value)
        const __m256 tolerance = _mm256_mul_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), sum),
                                               _mm256_set1_ps(kEdgeTolerance));
        const __m256 min_w = _mm256_min_ps(w0, _mm256_min_ps(w1, w2));
        const __m256 max_w = _mm256_max_ps(w0, _mm256_max_ps(w1, w2));
        const __m256 same_sign =
            _mm256_or_ps(_mm256_cmp_ps(min_w, _mm256_sub_ps(zero, tolerance), _CMP_GE_OQ),
                         _mm256_cmp_ps(max_w, tolerance, _CMP_LE_OQ));
        const unsigned lanes = (1u << count) - 1u;
        mask = unsigned(_mm256_movemask_ps(same_sign)) & lanes;
        if (mask == 0) return;  // the common case: the ray passes beside every triangle
        const Vec3x8 normal =
            cross(corners.corner[1] - corners.corner[0], corners.corner[2] - corners.corner[0]);
        const __m256 normal_dot_dir = dot(normal, ray.dir);
        t = _mm256_div_ps(dot(normal, a), normal_dot_dir);
        const __m256 valid =
            _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(sum, zero, _CMP_NEQ_OQ),
                                        _mm256_cmp_ps(normal_dot_dir, zero, _CMP_NEQ_OQ)),
                          _mm256_and_ps(_mm256_cmp_ps(t, _mm256_set1_ps(tnear), _CMP_GE_OQ),
                                        _mm256_cmp_ps(t, _mm256_set1_ps(tfar), _CMP_LE_OQ)));
        mask &= unsigned(_mm256_movemask_ps(valid));
    }
};

/// The Möller test: the steps of intersect_triangle_moller(), eight at a time, with w1, w2
/// the sign-corrected edge weights and `sum` |n.dir|. Its products and sums are Embree's AVX2
/// and AVX-512 kernels' own, fused the same way and in the same order (cross() and dot()
/// above): the drop-in finishes Embree's hit attributes from these terms (MollerTerms), so
/// changing the order of any operation here breaks its bit-identity with Embree
/// (EmbreeHitAttributes.TraversalTermsFinishToTheRecomputedAttributesBitForBit).
template <>
struct GroupTest<TriangleTest::moller> {
    unsigned mask = 0;
    __m256 w1, w2, sum, t;
    Vec3x8 normal;
    __m256 scaled_t;

    GroupTest(const GroupCorners& corners, std::uint32_t count, const TriangleGroupRay& ray,
              float tnear, float tfar) {
        // In an order that ends each value's use early (r before the edges, each edge's
        // weight right after it): with the edges, r, c and the normal all live at once the
        // test spilled at AVX2's 16 registers.
        const Vec3x8 c = corners.corner[0] - Vec3x8{ray.org[0], ray.org[1], ray.org[2]};
        const Vec3x8 r = cross(c, Vec3x8{ray.dir[0], ray.dir[1], ray.dir[2]});
        const Vec3x8 e2 = corners.corner[2] - corners.corner[0];
        const __m256 r_dot_e2 = dot(r, e2);
        const Vec3x8 e1 = corners.corner[0] - corners.corner[1];
        const __m256 r_dot_e1 = dot(r, e1);
        normal = cross(e2, e1);
        const __m256 den = dot(normal, ray.dir);
        const __m256 sign_bit = _mm256_set1_ps(-0.0f);
        const __m256 den_sign = _mm256_and_ps(den, sign_bit);
        sum = _mm256_andnot_ps(sign_bit, den);  // |den|
        w1 = _mm256_xor_ps(r_dot_e2, den_sign);
        w2 = _mm256_xor_ps(r_dot_e1, den_sign);
        const __m256 zero = _mm256_setzero_ps();
        const __m256 inside = _mm256_and_ps(
            _mm256_and_ps(_mm256_cmp_ps(w1, zero, _CMP_GE_OQ), _mm256_cmp_ps(w2, zero, _CMP_GE_OQ)),
            _mm256_and_ps(_mm256_cmp_ps(_mm256_add_ps(w1, w2), sum, _CMP_LE_OQ),
                          _mm256_cmp_ps(sum, zero, _CMP_NEQ_OQ)));
        mask = unsigned(_mm256_movemask_ps(inside)) & ((1u << count) - 1u);
        if (mask == 0) return;  // the common case: the ray passes beside every triangle
        scaled_t = _mm256_xor_ps(dot(normal, c), den_sign);
        t = _mm256_div_ps(scaled_t, sum);
        const __m256 in_range = _mm256_and_ps(_mm256_cmp_ps(t, _mm256_set1_ps(tnear), _CMP_GE_OQ),
                                              _mm256_cmp_ps(t, _mm256_set1_ps(tfar), _CMP_LE_OQ));
        mask &= unsigned(_mm256_movemask_ps(in_range));
    }
};

/// The closest lane of a test with at least one hit; on a tie the lower lane wins.
template <class Test>
TriangleGroupHit closest_lane(const Test& test) {
    alignas(32) float t[kTriangleGroupSize], w1[kTriangleGroupSize], w2[kTriangleGroupSize],
        sum[kTriangleGroupSize];
    _mm256_store_ps(t, test.t);
    unsigned mask = test.mask;
    std::uint32_t best = std::uint32_t(std::countr_zero(mask));
    for (mask &= mask - 1; mask; mask &= mask - 1) {
        const auto lane = std::uint32_t(std::countr_zero(mask));
        if (t[lane] < t[best]) best = lane;
    }
    _mm256_store_ps(w1, test.w1);
    _mm256_store_ps(w2, test.w2);
    _mm256_store_ps(sum, test.sum);
    const float inv_sum = 1.0f / sum[best];
    return {best, t[best], w1[best] * inv_sum, w2[best] * inv_sum};
}

/// The Möller terms of `lane` of a test.
inline MollerTerms moller_terms_of(const GroupTest<TriangleTest::moller>& test,
                                   std::uint32_t lane) {
    alignas(32) float values[7][kTriangleGroupSize];
    const __m256 rows[7] = {test.w1,       test.w2,       test.scaled_t, test.sum,
                            test.normal.x, test.normal.y, test.normal.z};
    for (int r = 0; r < 7; ++r) _mm256_store_ps(values[r], rows[r]);
    return {values[0][lane],
            values[1][lane],
            values[2][lane],
            values[3][lane],
            {values[4][lane], values[5][lane], values[6][lane]}};
}

/// Fills `terms` (when not null) with the hit lane's Möller terms; the watertight test has
/// none, and `terms` is left alone.
template <TriangleTest kTest>
void take_moller_terms(const GroupTest<kTest>& test, std::uint32_t lane, MollerTerms* terms) {
    if constexpr (kTest == TriangleTest::moller)
        if (terms != nullptr) *terms = moller_terms_of(test, lane);
}

}  // namespace triangle_group_detail

/// Closest hit among `count` (1..8) triangles from anywhere, `lanes[i]` pointing at the i-th
/// (e.g. the triangles of several small leaves, tested together), with tnear <= t <= tfar;
/// hit.index is the lane, and on a tie the lower lane wins. Returns false when none is hit.
/// With `terms` given, the Möller test also writes the hit's terms there (the watertight
/// test and the portable kernels have none and leave it alone).
template <TriangleTest kTest>
bool intersect_triangle_lanes(const TriangleVerts* const* lanes, std::uint32_t count,
                              const TriangleGroupRay& ray, float tnear, float tfar,
                              TriangleGroupHit& hit, MollerTerms* terms = nullptr) {
    using namespace triangle_group_detail;
    const GroupCorners corners([lanes](std::uint32_t i) { return lanes[i]; }, count);
    const GroupTest<kTest> test(corners, count, ray, tnear, tfar);
    if (test.mask == 0) return false;
    hit = closest_lane(test);
    take_moller_terms(test, hit.index, terms);
    return true;
}

/// True when the ray hits any of the `count` (1..8) triangles `lanes` points at within
/// [tnear, tfar].
template <TriangleTest kTest>
bool occluded_triangle_lanes(const TriangleVerts* const* lanes, std::uint32_t count,
                             const TriangleGroupRay& ray, float tnear, float tfar) {
    using namespace triangle_group_detail;
    const GroupCorners corners([lanes](std::uint32_t i) { return lanes[i]; }, count);
    return GroupTest<kTest>(corners, count, ray, tnear, tfar).mask != 0;
}

/// As intersect_triangle_lanes, for `count` triangles given as pre-arranged rows.
template <TriangleTest kTest>
bool intersect_triangle_rows(const __m256 (&rows)[9], std::uint32_t count,
                             const TriangleGroupRay& ray, float tnear, float tfar,
                             TriangleGroupHit& hit, MollerTerms* terms = nullptr) {
    using namespace triangle_group_detail;
    const GroupTest<kTest> test(GroupCorners(rows), count, ray, tnear, tfar);
    if (test.mask == 0) return false;
    hit = closest_lane(test);
    take_moller_terms(test, hit.index, terms);
    return true;
}

/// As occluded_triangle_lanes, for `count` triangles given as pre-arranged rows.
template <TriangleTest kTest>
bool occluded_triangle_rows(const __m256 (&rows)[9], std::uint32_t count,
                            const TriangleGroupRay& ray, float tnear, float tfar) {
    using namespace triangle_group_detail;
    return GroupTest<kTest>(GroupCorners(rows), count, ray, tnear, tfar).mask != 0;
}

#else  // portable path: the scalar test, one triangle after the other

/// The ray as the scalar test takes it.
struct TriangleGroupRay {
    Vec3f org, dir;
    TriangleGroupRay(Vec3f origin, Vec3f direction) : org(origin), dir(direction) {}
};

template <TriangleTest kTest>
bool intersect_triangle_lanes(const TriangleVerts* const* lanes, std::uint32_t count,
                              const TriangleGroupRay& ray, float tnear, float tfar,
                              TriangleGroupHit& hit, MollerTerms* /*terms: none here*/ = nullptr) {
    bool found = false;
    for (std::uint32_t i = 0; i < count; ++i) {
        float t, u, v;
        // Strictly closer hits only, so ties go to the lower lane as in the SIMD path.
        if (intersect_triangle_by<kTest>(*lanes[i], ray.org, ray.dir, tnear, tfar, t, u, v) &&
            (!found || t < hit.t)) {
            hit = {i, t, u, v};
            found = true;
        }
    }
    return found;
}

template <TriangleTest kTest>
bool occluded_triangle_lanes(const TriangleVerts* const* lanes, std::uint32_t count,
                             const TriangleGroupRay& ray, float tnear, float tfar) {
    for (std::uint32_t i = 0; i < count; ++i) {
        float t, u, v;
        if (intersect_triangle_by<kTest>(*lanes[i], ray.org, ray.dir, tnear, tfar, t, u, v))
            return true;
    }
    return false;
}

#endif

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
