#pragma once

#include "rebraid/core/ray.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/types.h"

namespace rebraid::viewer {

/// What shading needs about a hit, computed only from the ray, the hit's ids and the scene,
/// so every structure that finds the same triangle gives the same bits (structures differ in
/// how they compute t and the barycentrics: world space, object space, SIMD order).
struct SurfaceHit {
    InstanceId instance_id = kInvalidId;
    PrimId prim_id = kInvalidId;
    Vec3f position;  ///< on the world-space triangle's plane
    /// Unit geometric normal of the world-space triangle, turned to face the ray's origin
    /// (zero for a degenerate triangle).
    Vec3f normal;
    float u = 0.0f;  ///< barycentric weight of corner 1, clamped into the triangle
    float v = 0.0f;  ///< barycentric weight of corner 2
};

/// Rebuilds the hit on the world-space triangle (corners transformed by the instance):
/// the ray meets the triangle's plane at `position`. Falls back to the structure's t and
/// barycentrics when the ray runs parallel to a (degenerate) triangle. `hit` must be a hit.
SurfaceHit make_surface_hit(const Scene& scene, const Ray& ray, const Hit& hit);

}  // namespace rebraid::viewer
