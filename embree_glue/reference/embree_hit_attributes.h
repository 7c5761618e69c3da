#pragma once

#include <array>
#include <optional>

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
/// embree_hit_attributes on that hit, at a fraction of its cost. nullopt for the `separate`
/// arithmetic (whose unfused rounding the traversal does not share) and where a result is
/// not finite.
std::optional<EmbreeHitAttributes> embree_hit_attributes_from_terms(
    const MollerTerms& terms, EmbreeKernelArithmetic arithmetic);

}  // namespace rebraid::glue
