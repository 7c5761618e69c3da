#pragma once

// Where a hit says it is: the one definition the hit comparisons (hit_comparison.h), the
// fuzz targets' answer check (fuzz/answer_check.h) and the reference tests share. No
// GoogleTest, so the fuzz targets can include it.

#include <limits>

#include "rebraid/core/ray.h"
#include "rebraid/core/scene.h"

namespace rebraid::test {

/// Distance between the ray's point at hit.t and the point at barycentrics (u, v) on the
/// world-space triangle the hit names: small only when t, both ids, u and v all describe one
/// point. Infinite for ids the scene does not have.
inline float hit_point_error(const Scene& scene, const Ray& ray, const Hit& hit) {
    if (hit.instance_id >= scene.instances.size()) return std::numeric_limits<float>::infinity();
    const Instance& instance = scene.instances[hit.instance_id];
    const Mesh& mesh = scene.meshes[instance.mesh_id];
    if (hit.prim_id >= mesh.triangles.size()) return std::numeric_limits<float>::infinity();
    const auto [p0, p1, p2] = mesh.corners(hit.prim_id);
    const Vec3f on_triangle = instance.object_to_world.transform_point(p0 * (1.0f - hit.u - hit.v) +
                                                                       p1 * hit.u + p2 * hit.v);
    return length(ray.org + ray.dir * hit.t - on_triangle);
}

}  // namespace rebraid::test
