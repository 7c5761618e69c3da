#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/simd_config.h"
#include "rebraid/core/types.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// Byte offset inside a WideNode of the plane array of `axis` a ray enters boxes through
/// (`is_far` false) or leaves them through (true), for a direction of sign `is_negative`
/// along that axis: the lower planes first for a positive direction, the upper ones for a
/// negative one.
constexpr std::uint32_t slab_plane_offset(int axis, bool is_negative, bool is_far) {
    // WideNode stores each axis's lower plane array followed by its upper one.
    static_assert(offsetof(WideNode, upper_x) == offsetof(WideNode, lower_x) + 32 &&
                  offsetof(WideNode, lower_y) == offsetof(WideNode, lower_x) + 64 &&
                  offsetof(WideNode, upper_y) == offsetof(WideNode, lower_x) + 96 &&
                  offsetof(WideNode, lower_z) == offsetof(WideNode, lower_x) + 128 &&
                  offsetof(WideNode, upper_z) == offsetof(WideNode, lower_x) + 160);
    const bool is_upper = is_negative != is_far;
    return std::uint32_t(offsetof(WideNode, lower_x)) + 64u * std::uint32_t(axis) +
           32u * std::uint32_t(is_upper);
}

/// The plane offsets (slab_plane_offset) of each axis for one combination of direction signs.
struct SlabPlaneOffsets {
    std::uint32_t near[3];
    std::uint32_t far[3];
};

/// The offsets for the direction signs `negative_axes` (bit a set: negative along axis a).
constexpr SlabPlaneOffsets make_slab_plane_offsets(std::uint32_t negative_axes) {
    SlabPlaneOffsets offsets{};
    for (int a = 0; a < 3; ++a) {
        const bool is_negative = (negative_axes >> a) & 1u;
        offsets.near[a] = slab_plane_offset(a, is_negative, false);
        offsets.far[a] = slab_plane_offset(a, is_negative, true);
    }
    return offsets;
}

/// SlabPlaneOffsets for each value of TraversalRay::negative_axes: a box test looks its
/// offsets up once per ray instead of deriving six of them (which cost as many instructions
/// as a rejected ray's box test).
inline constexpr SlabPlaneOffsets kSlabPlaneOffsets[8] = {
    make_slab_plane_offsets(0), make_slab_plane_offsets(1), make_slab_plane_offsets(2),
    make_slab_plane_offsets(3), make_slab_plane_offsets(4), make_slab_plane_offsets(5),
    make_slab_plane_offsets(6), make_slab_plane_offsets(7)};

#ifdef REBRAID_SIMD_AVX2
/// 1 / direction per axis in lanes 0-2 (lane 3: 1), a component closer to zero than 1e-18
/// taken as 1e-18 of its sign, so that every reciprocal is finite.
inline __m128 reciprocal_directions(Vec3f direction) {
    const __m128 d = _mm_setr_ps(direction.x, direction.y, direction.z, 1.0f);
    const __m128 sign_bit = _mm_set1_ps(-0.0f);
    const __m128 tiny = _mm_set1_ps(1e-18f);
    const __m128 is_tiny = _mm_cmplt_ps(_mm_andnot_ps(sign_bit, d), tiny);
    const __m128 safe = _mm_blendv_ps(d, _mm_or_ps(_mm_and_ps(d, sign_bit), tiny), is_tiny);
    return _mm_div_ps(_mm_set1_ps(1.0f), safe);
}
#endif

/// How far a slab test moves the product org * rdir, for each unit of its size, so that the
/// fused form plane * rdir - org * rdir never rejects a box the ray touches: 4 units in the
/// last place of the product cover its rounding and that of the sums the shifts are formed
/// by (slab_shifts), with room to spare.
inline constexpr float kSlabShiftScale = 4.0f * 5.96046448e-08f;

/// The shifts of the fused slab test (Embree's form, made conservative): a plane's distance
/// along an axis is taken as fma(plane, rdir, shift), with `near` (-(org * rdir) - margin) for
/// the planes a ray enters boxes through and `far` (-(org * rdir) + margin) for those it
/// leaves them through. The margin bounds the rounding of org * rdir (kSlabShiftScale of its
/// size, at least the smallest normal float), so the exact value of each fused result lies on
/// the safe side of the exact distance (plane - org) * rdir, and rounding, being monotonic,
/// keeps every computed entry at most and every exit at least the rounded exact one: a box
/// the ray meets within [tnear, tfar] is never rejected, with no scale on tfar. (The product
/// of a far-away origin and rdir loses the small distances' precision; the margin, a few
/// units in the last place of the origin's coordinate, makes up for it.) An infinite product
/// gives infinite shifts of its sign, as the exact distances are.
struct SlabShifts {
    Vec3f near;
    Vec3f far;
};

/// SlabShifts of one axis (every kernel level forms them in this order: the same floats).
inline void slab_shifts(float org, float rdir, float& near_shift, float& far_shift) {
    const float product = org * rdir;
    const float margin = std::fmin(
        std::fmax(std::fabs(product) * kSlabShiftScale, std::numeric_limits<float>::min()),
        std::numeric_limits<float>::max());
    near_shift = -(product + margin);
    far_shift = margin - product;
}

#ifdef REBRAID_SIMD_AVX2
/// slab_shifts for the axes in the lanes of `org` and `reciprocal`, in those lanes.
inline void slab_shift_lanes(__m128 org, __m128 reciprocal, __m128& near_shift, __m128& far_shift) {
    const __m128 product = _mm_mul_ps(org, reciprocal);
    const __m128 size = _mm_andnot_ps(_mm_set1_ps(-0.0f), product);
    const __m128 margin = _mm_min_ps(_mm_max_ps(_mm_mul_ps(size, _mm_set1_ps(kSlabShiftScale)),
                                                _mm_set1_ps(std::numeric_limits<float>::min())),
                                     _mm_set1_ps(std::numeric_limits<float>::max()));
    near_shift = _mm_xor_ps(_mm_add_ps(product, margin), _mm_set1_ps(-0.0f));
    far_shift = _mm_sub_ps(margin, product);
}
#endif

/// The reciprocals of a ray's direction (reciprocal_directions) and the slab shifts of its
/// origin (slab_shift_lanes) as the box tests take them, made once per query: the root-box cull
/// (misses_root_box) and the prepared world ray both read them, where each used to form them
/// on its own (a division and the shifts twice on the path of every ray from outside the
/// scene's box). The portable kernels compute them in TraversalRay.
struct SlabTerms {
#ifdef REBRAID_SIMD_AVX2
    __m128 reciprocals;  ///< x, y, z, then 1
    __m128 near_shifts;  ///< SlabShifts::near in lanes 0-2
    __m128 far_shifts;   ///< SlabShifts::far in lanes 0-2
    SlabTerms(Vec3f origin, Vec3f direction)
        : SlabTerms(_mm_setr_ps(origin.x, origin.y, origin.z, 0.0f), direction) {}
    /// Of a query's ray: its origin in one load, lane 3 (tnear) cleared so that no value of
    /// it (a denormal costs a multiplication an assist) reaches the arithmetic, and the shifts
    /// a ray from outside the scene's box waits on before the cull start at once.
    explicit SlabTerms(const Ray& ray)
        : SlabTerms(_mm_blend_ps(_mm_loadu_ps(&ray.org.x), _mm_setzero_ps(), 8), ray.dir) {
        static_assert(offsetof(Ray, tnear) == offsetof(Ray, org) + 12);
    }

private:
    SlabTerms(__m128 origin, Vec3f direction) : reciprocals(reciprocal_directions(direction)) {
        slab_shift_lanes(origin, reciprocals, near_shifts, far_shifts);
    }
#else
    SlabTerms(Vec3f, Vec3f) {}
    explicit SlabTerms(const Ray&) {}
#endif
};

/// A ray prepared for box tests: reciprocal direction with zero components replaced by tiny
/// ones (so no 0 * inf appears) and the sign of each axis, from which a box test takes the
/// plane arrays the ray enters and leaves a box through (slab_plane_offset).
struct TraversalRay {
    Vec3f org;
    Vec3f dir;
    Vec3f rdir;
    float tnear = 0.0f;
    float tfar = 0.0f;
    /// Bit a set when the ray runs towards lower coordinates along axis a (rdir[a] is not
    /// >= 0, so a NaN counts as negative).
    std::uint32_t negative_axes = 0;
    /// The box tests' shifts (SlabShifts) for org and rdir.
    SlabShifts shifts;

    TraversalRay(Vec3f origin, Vec3f direction, float t_near, float t_far)
        : TraversalRay(origin, direction, t_near, t_far, SlabTerms(origin, direction)) {}
    /// With the slab terms of `origin` and `direction` already made.
    TraversalRay(Vec3f origin, Vec3f direction, float t_near, float t_far,
                 [[maybe_unused]] const SlabTerms& slab_terms)
        : org(origin), dir(direction), tnear(t_near), tfar(t_far) {
#ifdef REBRAID_SIMD_AVX2
        // The three axes in the lanes of one register: every ray and every entry into an
        // instance's space pays this set-up, and the scalar form (a branch and a division per
        // axis) cost as many instructions as a rejected ray's whole traversal. Same IEEE
        // operations per lane, so the same reciprocals.
        const __m128 reciprocal = slab_terms.reciprocals;
        alignas(16) float lanes[4];
        _mm_store_ps(lanes, reciprocal);
        rdir = {lanes[0], lanes[1], lanes[2]};
        negative_axes =
            std::uint32_t(_mm_movemask_ps(_mm_cmp_ps(reciprocal, _mm_setzero_ps(), _CMP_NGE_UQ))) &
            7u;
        alignas(16) float near_lanes[4], far_lanes[4];
        _mm_store_ps(near_lanes, slab_terms.near_shifts);
        _mm_store_ps(far_lanes, slab_terms.far_shifts);
        shifts = {{near_lanes[0], near_lanes[1], near_lanes[2]},
                  {far_lanes[0], far_lanes[1], far_lanes[2]}};
#else
        for (int a = 0; a < 3; ++a) {
            const float d = direction[a];
            const float safe = std::fabs(d) < 1e-18f ? std::copysign(1e-18f, d) : d;
            rdir[a] = 1.0f / safe;
            if (!(rdir[a] >= 0.0f)) negative_axes |= 1u << a;
            slab_shifts(origin[a], rdir[a], shifts.near[a], shifts.far[a]);
        }
#endif
    }

    const SlabPlaneOffsets& plane_offsets() const {
        return kSlabPlaneOffsets[negative_axes];
    }
};

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
