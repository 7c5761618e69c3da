#pragma once

// Compares one structure's answers with a reference's (Embree flat) ray by ray, without
// GoogleTest, so the libFuzzer target and the randomized tests share one definition of
// "disagree". Tolerances as tests/support/hit_comparison.h: t within 1e-4 relative plus a few ulps
// of the scene's magnitude. A ray whose closer hit is fragile may differ: near an edge (barycentric
// < 1e-2), on a sliver triangle (area below 1e-2 of its longest edge squared) or at a grazing angle
// (|cos| between ray and normal < 1e-2). There, whether and where the triangle is hit depends on
// rounding that differs between world-space vertices (flat structures) and object-space vertices
// behind a transform (instanced ones); the fuzzed scenes, with their quantised, often nearly
// degenerate triangles, hit such cases all the time, so the margins are wider than
// tests/support/hit_comparison.h's. A hit within rounding of tnear is fragile too.

#include <algorithm>
#include <cmath>
#include <span>
#include <sstream>
#include <string>

#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"

namespace rebraid::fuzz {

/// Tolerances of compare_answers().
struct AnswerTolerance {
    float relative_t = 1e-4f;
    float edge_graze = 1e-2f;
    float sliver_quality = 1e-2f;
    float grazing_cosine = 1e-2f;
};

/// True when `hit` is too close to an edge or on too thin a triangle for its presence to be
/// decided the same way by every structure.
inline bool is_fragile_hit(const Scene& scene, const Ray& ray, const Hit& hit,
                           const AnswerTolerance& tolerance) {
    if (!hit.is_hit()) return false;
    if (std::min({hit.u, hit.v, 1.0f - hit.u - hit.v}) < tolerance.edge_graze) return true;
    const Instance& instance = scene.instances[hit.instance_id];
    const std::array<Vec3f, 3> c = scene.meshes[instance.mesh_id].corners(hit.prim_id);
    const AffineTransform& xfm = instance.object_to_world;
    const Vec3f a = xfm.transform_point(c[0]), b = xfm.transform_point(c[1]),
                d = xfm.transform_point(c[2]);
    const float longest = std::max({dot(b - a, b - a), dot(d - b, d - b), dot(a - d, a - d)});
    const Vec3f normal = cross(b - a, d - a);
    const float area = length(normal);
    if (!(area >= tolerance.sliver_quality * longest)) return true;
    return std::fabs(dot(normal, ray.dir)) < tolerance.grazing_cosine * area * length(ray.dir);
}

/// Empty when `candidate` answers every ray as `reference` does (closest hit and occlusion)
/// within `tolerance`; otherwise a description of the first disagreement.
inline std::string compare_answers(const Scene& scene, const Accel& reference,
                                   const Accel& candidate, std::span<const Ray> rays,
                                   const AnswerTolerance& tolerance = {}) {
    const BBox3f bounds = scene.bounds();
    float magnitude = 0.0f;
    for (int axis = 0; axis < 3; ++axis)
        magnitude = std::max({magnitude, std::fabs(bounds.min[axis]), std::fabs(bounds.max[axis])});
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const Ray& ray = rays[i];
        const Hit expected = reference.intersect(ray);
        const Hit actual = candidate.intersect(ray);
        const bool is_occluded = candidate.occluded(ray);
        std::ostringstream why;
        why << "ray " << i << " (org " << ray.org.x << " " << ray.org.y << " " << ray.org.z
            << " dir " << ray.dir.x << " " << ray.dir.y << " " << ray.dir.z
            << "): expected t=" << expected.t << " inst=" << expected.instance_id
            << " prim=" << expected.prim_id << ", got t=" << actual.t
            << " inst=" << actual.instance_id << " prim=" << actual.prim_id
            << " occluded=" << is_occluded;
        if (is_occluded != actual.is_hit() && !is_fragile_hit(scene, ray, expected, tolerance))
            return "occluded() disagrees with intersect(): " + why.str();
        if (!expected.is_hit() && !actual.is_hit()) continue;
        if (expected.is_hit() && actual.is_hit()) {
            const float allowed =
                tolerance.relative_t * std::max(expected.t, actual.t) + magnitude * 0x1.0p-16f;
            if (std::fabs(expected.t - actual.t) <= allowed) continue;  // ids may differ on ties
        }
        // A hit at the very start of the segment (the origin lies on the triangle, to
        // within rounding of the scene's magnitude) may or may not be reported: Embree
        // gives no guarantee at tnear, and an instanced structure computes t in object space.
        const Hit& first = expected.t <= actual.t ? expected : actual;
        if (first.t - ray.tnear <= magnitude * 0x1.0p-16f) continue;
        // One of the two found a hit the other passed: fine only when that closer hit is
        // fragile.
        const Hit& closer = expected.t <= actual.t ? expected : actual;
        if (is_fragile_hit(scene, ray, closer, tolerance)) continue;
        return why.str();
    }
    return {};
}

}  // namespace rebraid::fuzz
