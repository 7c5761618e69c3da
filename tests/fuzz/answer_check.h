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
#include "support/hit_point.h"

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

/// What compare_answers() found on a batch of rays.
struct AnswerComparison {
    std::string disagreement;  ///< empty, or a description of the first disagreement
    std::size_t rays = 0;
    std::size_t hits = 0;              ///< rays the reference hits
    std::size_t ties = 0;              ///< same t, another triangle that is really hit there
    std::size_t excused_fragile = 0;   ///< differences excused on a fragile closer hit
    std::size_t excused_at_tnear = 0;  ///< differences excused at the start of the segment

    bool agrees() const { return disagreement.empty(); }
    /// Rays whose difference was excused, of every kind.
    std::size_t excused() const { return excused_fragile + excused_at_tnear; }
};

/// True when `hit`'s triangle, u and v name the point of the ray at hit.t (within 1e-4 of the
/// scene's magnitude plus of the distance travelled): the triangle is really hit there.
inline bool names_its_point(const Scene& scene, const Ray& ray, const Hit& hit, float magnitude) {
    return test::hit_point_error(scene, ray, hit) <= 1e-4f * (magnitude + length(ray.dir * hit.t));
}

/// Compares `candidate` with `reference` ray by ray (closest hit and occlusion) within
/// `tolerance`: the first disagreement, and how many rays hit, tied or were excused. A
/// different triangle at the same t is a tie only when both hits name a point on their
/// triangle there (or the candidate's closer hit is fragile).
inline AnswerComparison compare_answers(const Scene& scene, const Accel& reference,
                                        const Accel& candidate, std::span<const Ray> rays,
                                        const AnswerTolerance& tolerance = {}) {
    AnswerComparison result;
    const BBox3f bounds = scene.bounds();
    float magnitude = 0.0f;
    for (int axis = 0; axis < 3; ++axis)
        magnitude = std::max({magnitude, std::fabs(bounds.min[axis]), std::fabs(bounds.max[axis])});
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const Ray& ray = rays[i];
        const Hit expected = reference.intersect(ray);
        const Hit actual = candidate.intersect(ray);
        const bool is_occluded = candidate.occluded(ray);
        ++result.rays;
        result.hits += expected.is_hit();
        const auto describe = [&] {
            std::ostringstream why;
            why << "ray " << i << " (org " << ray.org.x << " " << ray.org.y << " " << ray.org.z
                << " dir " << ray.dir.x << " " << ray.dir.y << " " << ray.dir.z
                << "): expected t=" << expected.t << " inst=" << expected.instance_id
                << " prim=" << expected.prim_id << ", got t=" << actual.t
                << " inst=" << actual.instance_id << " prim=" << actual.prim_id
                << " occluded=" << is_occluded;
            return why.str();
        };
        if (is_occluded != actual.is_hit()) {
            if (!is_fragile_hit(scene, ray, expected, tolerance)) {
                result.disagreement = "occluded() disagrees with intersect(): " + describe();
                return result;
            }
            ++result.excused_fragile;
            continue;
        }
        if (!expected.is_hit() && !actual.is_hit()) continue;
        if (expected.is_hit() && actual.is_hit()) {
            const float allowed =
                tolerance.relative_t * std::max(expected.t, actual.t) + magnitude * 0x1.0p-16f;
            if (std::fabs(expected.t - actual.t) <= allowed) {
                const bool same_ids = expected.instance_id == actual.instance_id &&
                                      expected.prim_id == actual.prim_id;
                if (same_ids) continue;
                if (names_its_point(scene, ray, actual, magnitude) &&
                    names_its_point(scene, ray, expected, magnitude)) {
                    ++result.ties;
                    continue;
                }
                // Two triangles at the same t, one of them fragile: which of them is reported
                // depends on rounding (the fragile one's presence, and on a grazed triangle
                // its t), so either side may report either.
                if (is_fragile_hit(scene, ray, actual, tolerance) ||
                    is_fragile_hit(scene, ray, expected, tolerance)) {
                    ++result.excused_fragile;
                    continue;
                }
                result.disagreement = "another triangle at the same t: " + describe();
                return result;
            }
        }
        // A hit at the very start of the segment (the origin lies on the triangle, to
        // within rounding of the scene's magnitude) may or may not be reported: Embree
        // gives no guarantee at tnear, and an instanced structure computes t in object space.
        const Hit& closer = expected.t <= actual.t ? expected : actual;
        if (closer.t - ray.tnear <= magnitude * 0x1.0p-16f) {
            ++result.excused_at_tnear;
            continue;
        }
        // One of the two found a hit the other passed: fine only when that closer hit is
        // fragile.
        if (is_fragile_hit(scene, ray, closer, tolerance)) {
            ++result.excused_fragile;
            continue;
        }
        result.disagreement = describe();
        return result;
    }
    return result;
}

}  // namespace rebraid::fuzz
