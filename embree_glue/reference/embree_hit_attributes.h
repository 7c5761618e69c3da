#pragma once

#include <array>
#include <cmath>
#include <optional>

#if defined(__x86_64__) || defined(_M_X64) || defined(__i386__)
#include <immintrin.h>
#define REBRAID_GLUE_HAS_RCP_ESTIMATES 1
#endif

#include "rebraid/bvh/hit_triangle.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/transform.h"
#include "rebraid/core/types.h"

namespace rebraid::glue {

/// How Embree's ray kernels round on this machine. Embree 3.13 runs the kernels of the best
/// instruction set the CPU has: with AVX2 (and FMA) its multiply-adds are fused, with SSE or
/// AVX they round the product and the sum separately, and its AVX-512 kernels start the
/// reciprocal from the 14-bit estimate (rcp14) rather than the 12-bit one. Each is tested bit
/// for bit against rtcIntersect1 where the CPU runs it (EmbreeHitAttributes tests).
enum class EmbreeKernelArithmetic {
    separate,     ///< SSE4.2 and AVX kernels: a * b + c rounds twice
    fused,        ///< AVX2 kernels: a * b + c is one fused multiply-add
    fused_rcp14,  ///< AVX-512 kernels: fused, and the reciprocal starts from rcp14
};

/// The arithmetic of the kernels a default Embree device selects on this CPU: fused_rcp14
/// with the AVX-512 subsets Embree's AVX-512 kernels need (F, CD, DQ, BW, VL), fused with
/// AVX2 and FMA, else separate. A device created with an "isa=" configuration may select
/// others.
EmbreeKernelArithmetic detect_embree_kernel_arithmetic();

/// An instance's world-to-object map as Embree computes it from the float transform the
/// application registered: the adjugate of the linear part divided by its determinant, each
/// rounded to float in Embree's order, and the translation mapped through that matrix.
/// The caller checks that `object_to_world` is invertible.
AffineTransform embree_world_to_object(const AffineTransform& object_to_world);

/// The attributes rtcIntersect1 reports for a hit on a triangle.
struct EmbreeHitAttributes {
    float t = 0.0f;         ///< hit distance, in units of the ray's direction
    float u = 0.0f;         ///< barycentric weight of corner 1
    float v = 0.0f;         ///< barycentric weight of corner 2
    Vec3f geometry_normal;  ///< cross(v2 - v0, v0 - v1), unnormalised, in object space
};

/// The hardware's 12-bit reciprocal estimate (rcpss), the start of Embree's reciprocal in
/// its SSE, AVX and AVX2 kernels. The table is the CPU's own.
inline float embree_reciprocal_estimate_12(float x) {
#if defined(REBRAID_GLUE_HAS_RCP_ESTIMATES)
    return _mm_cvtss_f32(_mm_rcp_ss(_mm_set_ss(x)));
#else
    return 1.0f / x;
#endif
}

/// The 14-bit estimate (vrcp14ss) Embree's AVX-512 kernels start from. Compiled for AVX-512
/// on its own: call it only where the CPU has it (code compiled for AVX-512 inlines it).
#if defined(REBRAID_GLUE_HAS_RCP_ESTIMATES) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx512f"))) inline float embree_reciprocal_estimate_14(float x) {
    return _mm_cvtss_f32(_mm_rcp14_ss(_mm_setzero_ps(), _mm_set_ss(x)));
}
#else
inline float embree_reciprocal_estimate_14(float x) {
    return 1.0f / x;
}
#endif

/// Embree's attributes from a hit's Möller terms and its reciprocal of |n.dir|: each term
/// times the reciprocal; nullopt where a result is not finite.
inline std::optional<EmbreeHitAttributes> embree_attributes_from_reciprocal(
    const MollerTerms& terms, float reciprocal) {
    EmbreeHitAttributes hit;
    hit.t = terms.scaled_t * reciprocal;
    hit.u = terms.scaled_u * reciprocal;
    hit.v = terms.scaled_v * reciprocal;
    hit.geometry_normal = terms.normal;
    if (!std::isfinite(hit.t) || !std::isfinite(hit.u) || !std::isfinite(hit.v))
        return std::nullopt;
    return hit;
}

/// Embree's reciprocal of x in its fused kernels (AVX2, AVX-512), from the hardware estimate
/// `estimate` of 1 / x they start from: one Newton step, r + r * (1 - x * r), fused.
inline float embree_fused_reciprocal(float x, float estimate) {
    return std::fma(estimate, std::fma(-x, estimate, 1.0f), estimate);
}

/// The attributes of the hit of `world_ray` on the triangle `corners` (in object space),
/// computed as Embree 3.13's instance and triangle kernels compute them: the ray mapped to
/// object space with `world_to_object` (from embree_world_to_object; null for a triangle
/// geometry of the root scene, which Embree traces in world space), then the Möller-Trumbore
/// test with edges v0 - v1 and v2 - v0 and the determinant's reciprocal from the hardware
/// estimate refined by one Newton step, all in `arithmetic`.
///
/// The caller has found the hit (triangle and t) with its own traversal; this only
/// reproduces Embree's rounding. Returns nullopt when, in that arithmetic, the ray is
/// parallel to the triangle's plane or a result is not finite. u and v are clamped to be
/// non-negative, as Embree's test never reports them otherwise.
std::optional<EmbreeHitAttributes> embree_hit_attributes(const Ray& world_ray,
                                                         const AffineTransform* world_to_object,
                                                         const std::array<Vec3f, 3>& corners,
                                                         EmbreeKernelArithmetic arithmetic);

/// The attributes rtcIntersect1 reports for a hit whose Möller terms the project's SIMD
/// traversal computed (HitTriangle::moller_terms): in the fused arithmetics the traversal's
/// terms are Embree's own, bit for bit, when the ray was traced in the space Embree traces it
/// in (world space for a triangle geometry of the root scene; for an instance, the ray mapped
/// with embree_world_to_object's map, InstancedAccel::set_world_to_object), so only the
/// division remains: Embree's reciprocal of |n.dir| times each term. The same results as
/// embree_hit_attributes on that hit, at a fraction of its cost. Only for the fused
/// arithmetics (the `separate` one's unfused rounding the traversal does not share); nullopt
/// where a result is not finite. `estimate`: the estimate of 1 / terms.abs_den the arithmetic
/// starts from (embree_reciprocal_estimate_12 for fused, embree_reciprocal_estimate_14 for
/// fused_rcp14), computed by the caller, which is compiled for its instruction set so that all of
/// this inlines on every ray's path.
inline std::optional<EmbreeHitAttributes> embree_fused_attributes_from_terms(
    const MollerTerms& terms, float estimate) {
    return embree_attributes_from_reciprocal(terms,
                                             embree_fused_reciprocal(terms.abs_den, estimate));
}

}  // namespace rebraid::glue
