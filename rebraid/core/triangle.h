#pragma once

#include <array>
#include <cmath>

#include "rebraid/core/triangle_test.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// A triangle's three corners, stored in leaf order inside a BVH so a leaf's triangles are
/// contiguous in memory.
struct TriangleVerts {
    Vec3f v0, v1, v2;
};

/// Edge functions within this fraction of their sum count as zero (inside): rounding makes
/// the near-zero functions of the edges around a vertex take arbitrary signs, and a ray
/// through a shared vertex must still hit one of the triangles around it. One float epsilon,
/// as Embree's robust mode.
inline constexpr float kEdgeTolerance = 1.1920929e-07f;

/// Ray-triangle test with edge functions in Plücker form on origin-relative corners: for
/// the edge from p to q, dot(cross(p - q, p + q), dir). An edge shared by two triangles then
/// yields exactly negated values in both, so a ray through the edge hits at least one of
/// them (no cracks), and the tolerance kEdgeTolerance closes vertices the same way. Far-away
/// origins keep their precision: p - q is the short edge vector, so the cross product never
/// cancels two long, nearly parallel origin-relative vectors as cross(p, q) would. Returns
/// true and sets t, u, v (barycentric weights of v1 and v2, Embree's convention) when
/// tnear <= t <= tfar. Degenerate triangles never hit.
inline bool intersect_triangle(const TriangleVerts& tri, Vec3f org, Vec3f dir, float tnear,
                               float tfar, float& t, float& u, float& v) {
    const Vec3f a = tri.v0 - org, b = tri.v1 - org, c = tri.v2 - org;
    // Each corner's weight is the function of the edge opposite to it (twice the triple
    // product of dir with that edge's corners).
    const float w0 = dot(cross(b - c, b + c), dir);  // opposite v0
    const float w1 = dot(cross(c - a, c + a), dir);  // opposite v1
    const float w2 = dot(cross(a - b, a + b), dir);  // opposite v2
    const float sum = w0 + w1 + w2;
    const float tolerance = kEdgeTolerance * std::fabs(sum);
    const bool all_positive = w0 >= -tolerance && w1 >= -tolerance && w2 >= -tolerance;
    const bool all_negative = w0 <= tolerance && w1 <= tolerance && w2 <= tolerance;
    if (!all_positive && !all_negative) return false;
    if (sum == 0.0f) return false;  // ray parallel to the plane, or a degenerate triangle
    const Vec3f normal = cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
    const float normal_dot_dir = dot(normal, dir);
    if (normal_dot_dir == 0.0f) return false;
    const float hit_t = dot(normal, a) / normal_dot_dir;
    if (!(hit_t >= tnear && hit_t <= tfar)) return false;  // also rejects NaN
    const float inv_sum = 1.0f / sum;
    t = hit_t;
    u = w1 * inv_sum;
    v = w2 * inv_sum;
    return true;
}

/// Ray-triangle test after Möller and Trumbore, in the form of Embree's default mode: with
/// the edges e1 = v0 - v1 and e2 = v2 - v0, the normal n = e2 x e1 and c = v0 - org,
/// u = (c x dir).e2 / (n.dir), v = (c x dir).e1 / (n.dir) and t = n.c / (n.dir), each
/// compared after taking the sign of n.dir out, so that divisions wait for a hit. Not
/// watertight (TriangleTest::moller); same results as intersect_triangle otherwise, up to
/// rounding. Returns true and sets t, u, v when tnear <= t <= tfar.
inline bool intersect_triangle_moller(const TriangleVerts& tri, Vec3f org, Vec3f dir, float tnear,
                                      float tfar, float& t, float& u, float& v) {
    const Vec3f e1 = tri.v0 - tri.v1, e2 = tri.v2 - tri.v0;
    const Vec3f normal = cross(e2, e1);
    const Vec3f c = tri.v0 - org;
    const Vec3f r = cross(c, dir);
    const float den = dot(normal, dir);
    const float abs_den = std::fabs(den);
    const float sign = den < 0.0f ? -1.0f : 1.0f;
    const float scaled_u = sign * dot(r, e2), scaled_v = sign * dot(r, e1);
    if (!(den != 0.0f && scaled_u >= 0.0f && scaled_v >= 0.0f && scaled_u + scaled_v <= abs_den))
        return false;
    const float hit_t = sign * dot(normal, c) / abs_den;
    if (!(hit_t >= tnear && hit_t <= tfar)) return false;
    const float inv_den = 1.0f / abs_den;
    t = hit_t;
    u = scaled_u * inv_den;
    v = scaled_v * inv_den;
    return true;
}

/// The test `test` names.
template <TriangleTest test>
bool intersect_triangle_by(const TriangleVerts& tri, Vec3f org, Vec3f dir, float tnear, float tfar,
                           float& t, float& u, float& v) {
    if constexpr (test == TriangleTest::moller)
        return intersect_triangle_moller(tri, org, dir, tnear, tfar, t, u, v);
    else
        return intersect_triangle(tri, org, dir, tnear, tfar, t, u, v);
}

}  // namespace rebraid
