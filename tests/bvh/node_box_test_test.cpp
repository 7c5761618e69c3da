// Compiled with the library's kernel flags (AVX2 + FMA where the build has them), so that the
// node test below is the kernels' own.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "rebraid/bvh/node_box_test.h"
#include "rebraid/bvh/traversal_ray.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/ray.h"
#include "support/box_test_rays.h"

namespace rebraid {
namespace {

/// The ray's interval through `box` within [tnear, tfar], with the distances
/// (plane - org) * rdir for the ray's own reciprocals taken in long double: the difference of
/// these floats is exact there, its product with rdir rounded at 2^-64 of its size, far below
/// a float's 2^-24. The box is met where entry <= exit.
struct ExactInterval {
    long double entry, exit;
};

ExactInterval exact_interval(const TraversalRay& ray, const BBox3f& box) {
    long double entry = ray.tnear, exit = ray.tfar;
    for (int a = 0; a < 3; ++a) {
        const bool negative = (ray.negative_axes >> a) & 1u;
        const long double near_plane = negative ? box.max[a] : box.min[a];
        const long double far_plane = negative ? box.min[a] : box.max[a];
        const long double rdir = ray.rdir[a];
        entry = std::max(entry, (near_plane - ray.org[a]) * rdir);
        exit = std::min(exit, (far_plane - ray.org[a]) * rdir);
    }
    return {entry, exit};
}

/// Rays from far away (up to a million units, where the product org * rdir dwarfs the
/// distances across a box) that graze `box`: through a point on one of its edges or faces, so
/// that the exact interval is a single point or nearly.
std::vector<Ray> grazing_rays(std::mt19937& random, const BBox3f& box) {
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::uniform_real_distribution<float> fraction(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (const float distance : {1e3f, 3e4f, 1e6f}) {
        for (int i = 0; i < 24; ++i) {
            Vec3f point{box.min.x + fraction(random) * (box.max.x - box.min.x),
                        box.min.y + fraction(random) * (box.max.y - box.min.y),
                        box.min.z + fraction(random) * (box.max.z - box.min.z)};
            // Onto a face, or onto an edge where two faces meet.
            point[i % 3] = i & 8 ? box.max[i % 3] : box.min[i % 3];
            if (i % 2) point[(i + 1) % 3] = i & 16 ? box.max[(i + 1) % 3] : box.min[(i + 1) % 3];
            Vec3f away{unit(random), unit(random), unit(random)};
            away = away * (distance / std::max(1e-3f, length(away)));
            const Vec3f org = point + away;
            rays.push_back(Ray{org, 0.0f, point - org, std::numeric_limits<float>::infinity()});
        }
    }
    return rays;
}

TEST(NodeBoxTest, NeverRejectsABoxTheRayMeetsInExactArithmetic) {
    std::mt19937 random(20261207);
    std::size_t met = 0, grazing_met = 0, rejected = 0;
    for (int scene = 0; scene < 200; ++scene) {
        const std::vector<WideNode> nodes = test::random_root(random, 1 + scene % 8);
        const WideNode& node = nodes[0];
        std::vector<Ray> rays = test::rays_around(random, node);
        const std::size_t near_rays = rays.size();
        for (int c = 0; c < node.child_count(); ++c)
            for (const Ray& ray : grazing_rays(random, node.child_bounds(c))) rays.push_back(ray);
        for (std::size_t r = 0; r < rays.size(); ++r) {
            const Ray& ray = rays[r];
            const TraversalRay prepared(ray.org, ray.dir, ray.tnear, ray.tfar);
            const NodeBoxTest box_test(prepared);
            alignas(32) float distances[kBvhWidth];
            const unsigned mask = box_test(node, prepared.tfar, distances);
            for (int c = 0; c < node.child_count(); ++c) {
                const ExactInterval exact = exact_interval(prepared, node.child_bounds(c));
                if (!(exact.entry <= exact.exit)) {
                    rejected += ((mask >> c) & 1u) == 0;
                    continue;
                }
                ++(r < near_rays ? met : grazing_met);
                ASSERT_TRUE((mask >> c) & 1u)
                    << "scene " << scene << " child " << c << " ray org " << ray.org.x << " "
                    << ray.org.y << " " << ray.org.z << " dir " << ray.dir.x << " " << ray.dir.y
                    << " " << ray.dir.z << " interval " << ray.tnear << " " << ray.tfar;
                // The entry distance it reports (which orders the stack and is checked
                // against shortened rays) is never past the exact one's rounding.
                EXPECT_LE(distances[c], float(exact.entry)) << "scene " << scene << " child " << c;
            }
        }
    }
    EXPECT_GT(met, 1000u);
    EXPECT_GT(grazing_met, 1000u);
    EXPECT_GT(rejected, 1000u);  // and it does cull
}

}  // namespace
}  // namespace rebraid
