#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rebraid/bvh/wide_node.h"
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

/// The reciprocals of a ray's direction as the box tests take them (reciprocal_directions), made
/// once per query: the root-box cull (misses_root_box) and the prepared world ray both read them,
/// where each used to divide on its own (one division on the path of every ray from outside the
/// scene's box). The portable kernels compute them in TraversalRay.
struct DirectionReciprocals {
#ifdef REBRAID_SIMD_AVX2
    __m128 lanes;  ///< x, y, z, then 1
    explicit DirectionReciprocals(Vec3f direction) : lanes(reciprocal_directions(direction)) {}
#else
    explicit DirectionReciprocals(Vec3f) {}
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

    TraversalRay(Vec3f origin, Vec3f direction, float t_near, float t_far)
        : TraversalRay(origin, direction, t_near, t_far, DirectionReciprocals(direction)) {}
    /// With the reciprocals of `direction` already made.
    TraversalRay(Vec3f origin, Vec3f direction, float t_near, float t_far,
                 [[maybe_unused]] const DirectionReciprocals& reciprocals)
        : org(origin), dir(direction), tnear(t_near), tfar(t_far) {
#ifdef REBRAID_SIMD_AVX2
        // The three axes in the lanes of one register: every ray and every entry into an
        // instance's space pays this set-up, and the scalar form (a branch and a division per
        // axis) cost as many instructions as a rejected ray's whole traversal. Same IEEE
        // operations per lane, so the same reciprocals.
        const __m128 reciprocal = reciprocals.lanes;
        alignas(16) float lanes[4];
        _mm_store_ps(lanes, reciprocal);
        rdir = {lanes[0], lanes[1], lanes[2]};
        negative_axes =
            std::uint32_t(_mm_movemask_ps(_mm_cmp_ps(reciprocal, _mm_setzero_ps(), _CMP_NGE_UQ))) &
            7u;
#else
        for (int a = 0; a < 3; ++a) {
            const float d = direction[a];
            const float safe = std::fabs(d) < 1e-18f ? std::copysign(1e-18f, d) : d;
            rdir[a] = 1.0f / safe;
            if (!(rdir[a] >= 0.0f)) negative_axes |= 1u << a;
        }
#endif
    }

    const SlabPlaneOffsets& plane_offsets() const {
        return kSlabPlaneOffsets[negative_axes];
    }
};

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
