#pragma once

#include <cstddef>
#include <cstdint>

#include "rebraid/bvh/root_box.h"
#include "rebraid/bvh/traversal_ray.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/simd_config.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// Whether the ray surely misses every child of the BVH's root, told from `box` (RootBox)
/// before the query prepares its ray: the preparation (broadcast origin, multipliers and
/// triangle-test vectors, a frame of locals) costs a ray that misses the scene more than the
/// root's box test itself, and on the primary rays of a scene small in its frame most rays
/// do. The slab test of NodeBoxTest (the same reciprocals and shifts, SlabShifts) on the union
/// of the root's child boxes, with float max and min: its entry is never later and its exit
/// never earlier than a child's, so every ray the node test lets into a child passes.
/// (NodeBoxTest's integer max and min let in a few rays more that meet no box, a -0 distance
/// counting as the least: rays outside it that move away.)
/// A NaN in the ray answers a miss, as the traversal does. The portable kernels reject
/// nothing here.
/// `slab_terms` are those of ray.org and ray.dir.
inline bool misses_root_box([[maybe_unused]] const RootBox& box, [[maybe_unused]] const Ray& ray,
                            [[maybe_unused]] const SlabTerms& slab_terms) {
#ifdef REBRAID_SIMD_AVX2
    static_assert(offsetof(Ray, tnear) == offsetof(Ray, org) + 12 &&
                  offsetof(Ray, tfar) == offsetof(Ray, dir) + 12);
    const __m128 lower = _mm_load_ps(box.lower), upper = _mm_load_ps(box.upper);
    const __m128 org = _mm_loadu_ps(&ray.org.x);  // lane 3: tnear
    // A ray from inside the box (a secondary ray, mostly, and every ray where the box is all
    // of space) is left to the traversal: the test would rarely reject it, and costs about 45
    // instructions (AVX2).
    const int inside = _mm_movemask_ps(
        _mm_and_ps(_mm_cmp_ps(org, lower, _CMP_GE_OQ), _mm_cmp_ps(org, upper, _CMP_LE_OQ)));
    if ((inside & 7) == 7) return false;
    const __m128 reciprocal = slab_terms.reciprocals;
    const __m128 is_negative = _mm_cmp_ps(reciprocal, _mm_setzero_ps(), _CMP_NGE_UQ);
    const __m128 near_plane = _mm_blendv_ps(lower, upper, is_negative);
    const __m128 far_plane = _mm_blendv_ps(upper, lower, is_negative);
    // The node test's shifts: the same floats in lanes 0-2.
    const __m128 near_shift = slab_terms.near_shifts, far_shift = slab_terms.far_shifts;
    // Lane 3 takes the ray's own interval, as the node test's fourth operand of max and min.
    const __m128 dir = _mm_loadu_ps(&ray.dir.x);  // lane 3: tfar
    const __m128 near = _mm_blend_ps(_mm_fmadd_ps(near_plane, reciprocal, near_shift), org, 8);
    const __m128 far = _mm_blend_ps(_mm_fmadd_ps(far_plane, reciprocal, far_shift), dir, 8);
    const __m128 near_2 = _mm_max_ps(near, _mm_permute_ps(near, 0x4e));
    const __m128 far_2 = _mm_min_ps(far, _mm_permute_ps(far, 0x4e));
    const __m128 entry = _mm_max_ps(near_2, _mm_permute_ps(near_2, 0xb1));
    const __m128 exit = _mm_min_ps(far_2, _mm_permute_ps(far_2, 0xb1));
    return !(_mm_comile_ss(entry, exit) != 0);
#else
    return false;
#endif
}

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
