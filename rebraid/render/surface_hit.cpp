#include "rebraid/render/surface_hit.h"

#include <algorithm>
#include <cmath>

namespace rebraid::viewer {

SurfaceHit make_surface_hit(const Scene& scene, const Ray& ray, const Hit& hit) {
    const Instance& instance = scene.instances[hit.instance_id];
    const auto corners = scene.meshes[instance.mesh_id].corners(hit.prim_id);
    const Vec3f p0 = instance.object_to_world.transform_point(corners[0]);
    const Vec3f e1 = instance.object_to_world.transform_point(corners[1]) - p0;
    const Vec3f e2 = instance.object_to_world.transform_point(corners[2]) - p0;
    const Vec3f n = cross(e1, e2);
    const float n_length = length(n);

    SurfaceHit surface;
    surface.instance_id = hit.instance_id;
    surface.prim_id = hit.prim_id;
    surface.u = hit.u;
    surface.v = hit.v;
    surface.position = ray.org + ray.dir * hit.t;
    if (!(n_length > 0.0f)) return surface;

    surface.normal = n / n_length;
    if (dot(surface.normal, ray.dir) > 0.0f) surface.normal = -surface.normal;
    const float facing = dot(n, ray.dir);
    if (!(std::fabs(facing) > 1e-30f)) return surface;
    const float t = dot(n, p0 - ray.org) / facing;
    if (!std::isfinite(t)) return surface;
    surface.position = ray.org + ray.dir * t;

    // Barycentrics of the plane point by least squares on the two edges (exact in the plane).
    const Vec3f w = surface.position - p0;
    const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    const float w1 = dot(w, e1), w2 = dot(w, e2);
    const float determinant = d11 * d22 - d12 * d12;
    if (!(determinant > 0.0f)) return surface;
    float u = (d22 * w1 - d12 * w2) / determinant;
    float v = (d11 * w2 - d12 * w1) / determinant;
    // The structure found this triangle; rounding may put the point a hair outside.
    u = std::clamp(u, 0.0f, 1.0f);
    v = std::clamp(v, 0.0f, 1.0f);
    if (u + v > 1.0f) {
        const float sum = u + v;
        u /= sum;
        v /= sum;
    }
    surface.u = u;
    surface.v = v;
    return surface;
}

}  // namespace rebraid::viewer
