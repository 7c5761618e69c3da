#pragma once

// Comparing a structure that traces instances' triangles without entering the instances
// (merged copies, a world tree) with one that enters them, on the same rays: each triangle is
// tested with the ray mapped as entering its instance maps it, so the answers agree to the bit.

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "rebraid/core/simd_level.h"
#include "rebraid/core/triangle_test.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid::test {

/// At every kernel level this machine runs and with both triangle tests: the same closest-hit
/// t to the bit and the same occlusion on every ray; the same triangle on all but 1 % of the
/// hits (two triangles hit at the same t, a shared edge, may be found in another order: a tie
/// either may win), and there the same u to the bit; the plain query names the located one's
/// triangle; and enough hits that the comparison is not one of misses. With
/// `same_leaf_positions`, the two also keep the hit triangle at the same leaf position (the
/// same object BVHs' arrays).
inline void expect_hits_as_entering(InstancedAccel& traced, InstancedAccel& entered,
                                    const std::vector<Ray>& rays, bool same_leaf_positions) {
    for (const TriangleTest test : {TriangleTest::moller, TriangleTest::watertight}) {
        for (const SimdLevel level : runnable_simd_levels()) {
            SCOPED_TRACE(std::string(simd_level_name(level)) + " / " +
                         std::string(triangle_test_name(test)));
            for (InstancedAccel* accel : {&traced, &entered}) {
                accel->set_simd_level(level);
                accel->set_triangle_test(test);
            }
            std::size_t hits = 0, differing = 0, other_triangle = 0;
            for (const Ray& ray : rays) {
                const LocatedHit a = traced.intersect_located(ray);
                const LocatedHit b = entered.intersect_located(ray);
                hits += a.hit.is_hit();
                const bool same = std::bit_cast<std::uint32_t>(a.hit.t) ==
                                      std::bit_cast<std::uint32_t>(b.hit.t) &&
                                  traced.occluded(ray) == entered.occluded(ray);
                if (!same && differing++ < 5) ADD_FAILURE() << "t " << a.hit.t << " / " << b.hit.t;
                const bool same_triangle =
                    a.hit.instance_id == b.hit.instance_id && a.hit.prim_id == b.hit.prim_id &&
                    (!same_leaf_positions || a.triangle.leaf_position == b.triangle.leaf_position);
                other_triangle += !same_triangle;
                if (a.hit.is_hit() && same_triangle) {
                    EXPECT_EQ(std::bit_cast<std::uint32_t>(a.hit.u),
                              std::bit_cast<std::uint32_t>(b.hit.u));
                }
                const Hit plain = traced.intersect(ray);
                EXPECT_EQ(plain.instance_id, a.hit.instance_id);
                EXPECT_EQ(plain.prim_id, a.hit.prim_id);
            }
            EXPECT_LE(other_triangle, hits / 100);
            EXPECT_EQ(differing, 0u);
            EXPECT_GT(hits, rays.size() / 50);
        }
    }
}

}  // namespace rebraid::test
