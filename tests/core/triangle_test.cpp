// The scalar ray-triangle tests (rebraid/core/triangle.h): barycentric convention, segment
// limits and degenerate triangles for both; watertight shared edges and far-away origins for
// the watertight one; the Möller test against it away from edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "rebraid/core/random.h"
#include "rebraid/core/triangle.h"

namespace rebraid {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct TriangleHit {
    bool is_hit = false;
    float t = 0.0f, u = 0.0f, v = 0.0f;
};

TriangleHit trace(const TriangleVerts& tri, Vec3f org, Vec3f dir, float tnear = 0.0f,
                  float tfar = kInf, TriangleTest test = TriangleTest::watertight) {
    TriangleHit hit;
    hit.is_hit = test == TriangleTest::watertight
                     ? intersect_triangle(tri, org, dir, tnear, tfar, hit.t, hit.u, hit.v)
                     : intersect_triangle_moller(tri, org, dir, tnear, tfar, hit.t, hit.u, hit.v);
    return hit;
}

constexpr TriangleTest kBothTests[] = {TriangleTest::watertight, TriangleTest::moller};

TEST(Triangle, HitReportsDistanceAndWeightsOfCorners1And2) {
    for (TriangleTest test : kBothTests) {
        SCOPED_TRACE(triangle_test_name(test));
        const TriangleVerts tri{{0, 0, 0}, {4, 0, 0}, {0, 2, 0}};
        // The point 0.25 * v1 + 0.5 * v2 = (1, 1, 0), approached from z = 3 along -z, and
        // from below (the other winding as the ray sees it).
        for (const float side : {1.0f, -1.0f}) {
            const TriangleHit hit = trace(tri, {1, 1, 3 * side}, {0, 0, -side}, 0.0f, kInf, test);
            ASSERT_TRUE(hit.is_hit);
            EXPECT_NEAR(hit.t, 3.0f, 1e-6f);
            EXPECT_NEAR(hit.u, 0.25f, 1e-6f);
            EXPECT_NEAR(hit.v, 0.5f, 1e-6f);
        }
    }
}

TEST(Triangle, BothSidesAreHitAndTIsInUnitsOfTheDirection) {
    for (TriangleTest test : kBothTests) {
        SCOPED_TRACE(triangle_test_name(test));
        const TriangleVerts tri{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        const TriangleHit front = trace(tri, {0.2f, 0.2f, 2}, {0, 0, -4}, 0.0f, kInf, test);
        const TriangleHit back = trace(tri, {0.2f, 0.2f, -2}, {0, 0, 4}, 0.0f, kInf, test);
        ASSERT_TRUE(front.is_hit);
        ASSERT_TRUE(back.is_hit);
        EXPECT_NEAR(front.t, 0.5f, 1e-6f);  // direction of length 4: distance 2 is t = 0.5
        EXPECT_NEAR(back.t, 0.5f, 1e-6f);
    }
}

TEST(Triangle, RespectsTheSegmentAndMissesBesideTheTriangle) {
    for (TriangleTest test : kBothTests) {
        SCOPED_TRACE(triangle_test_name(test));
        const TriangleVerts tri{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        EXPECT_FALSE(trace(tri, {0.2f, 0.2f, 2}, {0, 0, -1}, 0.0f, 1.9f, test).is_hit);
        EXPECT_FALSE(trace(tri, {0.2f, 0.2f, 2}, {0, 0, -1}, 2.1f, kInf, test).is_hit);
        EXPECT_TRUE(trace(tri, {0.2f, 0.2f, 2}, {0, 0, -1}, 1.9f, 2.1f, test).is_hit);
        // The segment's ends are inside it: a hit at exactly tnear or tfar counts.
        EXPECT_TRUE(trace(tri, {0.2f, 0.2f, 2}, {0, 0, -1}, 2.0f, 2.0f, test).is_hit);
        // Beyond the hypotenuse, pointing away, inside the plane.
        EXPECT_FALSE(trace(tri, {0.6f, 0.6f, 2}, {0, 0, -1}, 0.0f, kInf, test).is_hit);
        EXPECT_FALSE(trace(tri, {0.2f, 0.2f, 2}, {0, 0, 1}, 0.0f, kInf, test).is_hit);
        EXPECT_FALSE(trace(tri, {0.2f, 0.2f, 0}, {1, 0, 0}, 0.0f, kInf, test).is_hit);
    }
}

TEST(Triangle, DegenerateTrianglesNeverHit) {
    const Vec3f a{0.5f, 0.5f, 0.5f}, b{0.6f, 0.6f, 0.6f}, c{0.7f, 0.7f, 0.7f};
    const std::vector<TriangleVerts> degenerate = {{a, a, a}, {a, b, c}, {b, b, a}};
    Random random(3);
    for (const TriangleVerts& tri : degenerate) {
        for (int i = 0; i < 1000; ++i) {
            // Rays aimed straight at the degenerate triangle's points.
            const float s = random.next_float01();
            const Vec3f target = a + (c - a) * s;
            const Vec3f org{random.next_float(-2, 2), random.next_float(-2, 2),
                            random.next_float(-2, 2)};
            for (TriangleTest test : kBothTests)
                EXPECT_FALSE(trace(tri, org, target - org, 0.0f, kInf, test).is_hit)
                    << triangle_test_name(test);
        }
    }
}

/// Two triangles sharing the edge p-q, wound consistently (the edge runs p->q in one, q->p
/// in the other), tilted so they do not lie in one plane.
struct TrianglePair {
    TriangleVerts first, second;
};

TrianglePair random_pair(Random& random, Vec3f offset, float size) {
    const auto point = [&] {
        return offset + Vec3f{random.next_float(-size, size), random.next_float(-size, size),
                              random.next_float(-size, size)};
    };
    const Vec3f p = point(), q = point(), r = point(), s = point();
    return {{p, q, r}, {q, p, s}};
}

/// Double-precision weights (of p, q, r) of the line org + t * dir crossing triangle p, q, r,
/// divided by their sum; false when the line is parallel to the plane.
bool line_weights(Vec3f p, Vec3f q, Vec3f r, Vec3f org, Vec3f dir, double weights[3]) {
    const auto rel = [&](Vec3f x) {
        return std::array<double, 3>{double(x.x) - org.x, double(x.y) - org.y, double(x.z) - org.z};
    };
    const auto triple = [&](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        // dot(cross(a, b), dir)
        return (a[1] * b[2] - a[2] * b[1]) * dir.x + (a[2] * b[0] - a[0] * b[2]) * dir.y +
               (a[0] * b[1] - a[1] * b[0]) * dir.z;
    };
    const auto a = rel(p), b = rel(q), c = rel(r);
    weights[0] = triple(b, c);
    weights[1] = triple(c, a);
    weights[2] = triple(a, b);
    const double sum = weights[0] + weights[1] + weights[2];
    if (sum == 0.0) return false;
    for (int i = 0; i < 3; ++i) weights[i] /= sum;
    return true;
}

/// Rays aimed at points of the shared edge from random origins `distance` away. The float
/// ray may pass a rounding error beside its target, so which rays must hit is decided in
/// double precision on the ray as given: those crossing one of the triangles at least
/// `margin` (in barycentric weight) away from its two outer edges, where the pair, seen from
/// the origin, lies on both sides of the shared edge (no fold: else the edge is a silhouette
/// and grazing it may miss). Those must hit at least one triangle, at t ~ 1.
void expect_watertight_pairs(Vec3f offset, float size, float distance, double margin,
                             std::uint64_t seed) {
    Random random(seed);
    int tested = 0, holes = 0;
    for (int pair_index = 0; pair_index < 200; ++pair_index) {
        const TrianglePair pair = random_pair(random, offset, size);
        const Vec3f p = pair.first.v0, q = pair.first.v1, r = pair.first.v2, s = pair.second.v2;
        for (int i = 0; i < 50; ++i) {
            const float along = random.next_float(0.1f, 0.9f);
            const Vec3f target = p + (q - p) * along;
            const Vec3f away = normalize(Vec3f{random.next_float(-1, 1), random.next_float(-1, 1),
                                               random.next_float(-1, 1)});
            const Vec3f org = target + away * distance;
            const Vec3f dir = target - org;
            double first[3], second[3];  // weights of (p, q, r) and of (q, p, s)
            if (!line_weights(p, q, r, org, dir, first) || !line_weights(q, p, s, org, dir, second))
                continue;
            // Not folded: r and s have opposite weights relative to the shared edge's line
            // crossing, i.e. the line crosses one plane inside and the other outside it.
            const bool unfolded = (first[2] >= 0.0) != (second[2] >= 0.0);
            const bool crosses_first = first[2] >= 0.0 && first[0] >= margin && first[1] >= margin;
            const bool crosses_second =
                second[2] >= 0.0 && second[0] >= margin && second[1] >= margin;
            // Nor seen nearly edge-on, where no float test resolves the triangle.
            const auto facing = [&](const TriangleVerts& tri) {
                const Vec3f normal = cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
                return std::fabs(dot(normal, dir)) > 0.2f * length(normal) * length(dir);
            };
            if (!unfolded || !(crosses_first || crosses_second) || !facing(pair.first) ||
                !facing(pair.second))
                continue;
            ++tested;
            const TriangleHit a = trace(pair.first, org, dir);
            const TriangleHit b = trace(pair.second, org, dir);
            if (!a.is_hit && !b.is_hit) ++holes;
            if (a.is_hit) {
                EXPECT_NEAR(a.t, 1.0f, 1e-3f);
            }
            if (b.is_hit) {
                EXPECT_NEAR(b.t, 1.0f, 1e-3f);
            }
        }
    }
    EXPECT_GT(tested, 1000);
    EXPECT_EQ(holes, 0) << "rays slipped through a shared edge";
}

TEST(Triangle, SharedEdgesAreWatertight) {
    expect_watertight_pairs({0, 0, 0}, 1.0f, 3.0f, 1e-6, 11);
}

TEST(Triangle, FarAwayOriginsLoseNoEdgeHits) {
    // Unit-sized triangles seen from 2000 away, the second pair far from the coordinate
    // origin too: the origin-relative corners are long, nearly parallel vectors (a cross
    // product of two of them would cancel catastrophically). Float precision bounds how far
    // this can go: the edge functions' relative error grows like 1e-7 * distance / size.
    expect_watertight_pairs({0, 0, 0}, 1.0f, 2e3f, 1e-2, 12);
    expect_watertight_pairs({2e4f, -3e4f, 1e4f}, 1.0f, 2e3f, 1e-2, 13);
}

TEST(Triangle, FarAwayOriginsKeepAccurateDistances) {
    Random random(17);
    for (int i = 0; i < 1000; ++i) {
        const TriangleVerts tri{{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
        const Vec3f target{random.next_float(-0.3f, 0.3f), random.next_float(-0.5f, 0.3f), 0.0f};
        const Vec3f org{random.next_float(-1e5f, 1e5f), random.next_float(-1e5f, 1e5f), 1e5f};
        const Vec3f dir = normalize(target - org);
        const TriangleHit hit = trace(tri, org, dir);
        ASSERT_TRUE(hit.is_hit) << "ray " << i;
        const double dx = double(target.x) - org.x, dy = double(target.y) - org.y,
                     dz = double(target.z) - org.z;
        const double distance = std::sqrt(dx * dx + dy * dy + dz * dz);
        EXPECT_NEAR(hit.t, distance, 1e-4 * distance);
    }
}

TEST(Triangle, MollerTestAgreesWithTheWatertightOneAwayFromEdges) {
    // Random triangles and rays: both tests hit the same triangles, at the same t, u and v up
    // to rounding, wherever the ray passes clear of the edges (all weights above 1e-3).
    Random random(17);
    int compared = 0, hits = 0;
    for (int i = 0; i < 20000; ++i) {
        const auto point = [&] {
            return Vec3f{random.next_float(-1, 1), random.next_float(-1, 1),
                         random.next_float(-1, 1)};
        };
        const TriangleVerts tri{point(), point(), point()};
        const Vec3f org = point() * 3.0f, target = point();
        const TriangleHit watertight = trace(tri, org, target - org);
        const TriangleHit moller = trace(tri, org, target - org, 0.0f, kInf, TriangleTest::moller);
        if (watertight.is_hit &&
            std::min({watertight.u, watertight.v, 1.0f - watertight.u - watertight.v}) < 1e-3f)
            continue;
        ++compared;
        ASSERT_EQ(moller.is_hit, watertight.is_hit) << "ray " << i;
        if (!moller.is_hit) continue;
        ++hits;
        EXPECT_NEAR(moller.t, watertight.t, 1e-4f * watertight.t) << "ray " << i;
        EXPECT_NEAR(moller.u, watertight.u, 1e-4f) << "ray " << i;
        EXPECT_NEAR(moller.v, watertight.v, 1e-4f) << "ray " << i;
    }
    EXPECT_GT(compared, 19000);
    EXPECT_GT(hits, 1000);  // the comparison covers hits, not only misses
}

}  // namespace
}  // namespace rebraid
