// Compiled with the library's kernel flags (AVX2 + FMA where the build has them), so that the
// cull and the node test below are the kernels' own.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "rebraid/bvh/root_box.h"
#include "rebraid/bvh/root_box_cull.h"
#include "rebraid/bvh/traversal_ray.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/ray.h"
#include "support/box_test_rays.h"

namespace rebraid {
namespace {

/// Whether the slab test of NodeBoxTest, in float arithmetic, lets the ray into `child`: the
/// same reciprocals and shifts (SlabShifts), float max and min. (NodeBoxTest takes max and min
/// on the floats' bits, which lets in a few rays more that meet no box.)
bool enters(const TraversalRay& ray, const BBox3f& child) {
    float entry = ray.tnear, exit = ray.tfar;
    for (int a = 0; a < 3; ++a) {
        const bool negative = (ray.negative_axes >> a) & 1u;
        const float near_plane = negative ? child.max[a] : child.min[a];
        const float far_plane = negative ? child.min[a] : child.max[a];
        entry = std::max(entry, std::fma(near_plane, ray.rdir[a], ray.shifts.near[a]));
        exit = std::min(exit, std::fma(far_plane, ray.rdir[a], ray.shifts.far[a]));
    }
    return entry <= exit;
}

TEST(RootBoxCull, NeverRejectsARayTheRootsSlabTestLetsIntoAChild) {
    std::mt19937 random(20261206);
    std::size_t rejected = 0, entered = 0;
    for (int scene = 0; scene < 200; ++scene) {
        const std::vector<WideNode> nodes = test::random_root(random, 1 + scene % 8);
        const RootBox box = root_box_of(nodes, NodeRef::inner(0));
        for (const Ray& ray : test::rays_around(random, nodes[0])) {
            const TraversalRay prepared(ray.org, ray.dir, ray.tnear, ray.tfar);
            bool any_child = false;
            for (int c = 0; c < nodes[0].child_count(); ++c)
                any_child = any_child || enters(prepared, nodes[0].child_bounds(c));
            const bool misses = misses_root_box(box, ray, SlabTerms(ray.org, ray.dir));
            if (any_child) {
                ++entered;
                ASSERT_FALSE(misses)
                    << "scene " << scene << " ray org " << ray.org.x << " " << ray.org.y << " "
                    << ray.org.z << " dir " << ray.dir.x << " " << ray.dir.y << " " << ray.dir.z
                    << " interval " << ray.tnear << " " << ray.tfar;
            }
            rejected += misses;
        }
    }
    EXPECT_GT(entered, 1000u);
#ifdef REBRAID_SIMD_AVX2
    // The SIMD kernels cull: most rays that miss every child miss the union box too.
    EXPECT_GT(rejected, 1000u);
#else
    EXPECT_EQ(rejected, 0u);  // the portable kernels leave every ray to the traversal
#endif
}

TEST(SlabTerms, AQueryRaysTermsAreThoseOfItsOriginAndDirectionWhateverItsTnear) {
    // The query's form reads the ray's origin with tnear beside it in one load; tnear must
    // reach none of the terms (a denormal would cost the multiplications an assist).
    std::mt19937 random(23);
    const std::vector<WideNode> nodes = test::random_root(random, 8);
    const float tnears[] = {0.0f, 1e-40f, 0.5f, std::numeric_limits<float>::infinity(),
                            std::numeric_limits<float>::quiet_NaN()};
    std::size_t checked = 0;
    for (Ray ray : test::rays_around(random, nodes[0])) {
        for (const float tnear : tnears) {
            ray.tnear = tnear;
            const SlabTerms from_ray(ray), from_parts(ray.org, ray.dir);
#ifdef REBRAID_SIMD_AVX2
            const auto same_bits = [](__m128 a, __m128 b) {
                return _mm_movemask_epi8(
                           _mm_cmpeq_epi32(_mm_castps_si128(a), _mm_castps_si128(b))) == 0xffff;
            };
            ASSERT_TRUE(same_bits(from_ray.reciprocals, from_parts.reciprocals));
            ASSERT_TRUE(same_bits(from_ray.near_shifts, from_parts.near_shifts));
            ASSERT_TRUE(same_bits(from_ray.far_shifts, from_parts.far_shifts));
#endif
            // And the prepared ray is the one made without shared terms.
            const TraversalRay shared(ray.org, ray.dir, ray.tnear, ray.tfar, from_ray);
            const TraversalRay alone(ray.org, ray.dir, ray.tnear, ray.tfar);
            for (int a = 0; a < 3; ++a) {
                ASSERT_EQ(std::bit_cast<std::uint32_t>(shared.rdir[a]),
                          std::bit_cast<std::uint32_t>(alone.rdir[a]));
                ASSERT_EQ(std::bit_cast<std::uint32_t>(shared.shifts.near[a]),
                          std::bit_cast<std::uint32_t>(alone.shifts.near[a]));
                ASSERT_EQ(std::bit_cast<std::uint32_t>(shared.shifts.far[a]),
                          std::bit_cast<std::uint32_t>(alone.shifts.far[a]));
            }
            ASSERT_EQ(shared.negative_axes, alone.negative_axes);
            ++checked;
        }
    }
    EXPECT_GT(checked, 1000u);
}

TEST(RootBoxCull, RejectsNothingWhereTheRootIsALeaf) {
    const std::vector<WideNode> nodes(1, WideNode::make_empty());
    const RootBox box = root_box_of(nodes, NodeRef::leaf(0, 3));
    for (const Vec3f org : {Vec3f{0, 0, 0}, Vec3f{1e30f, -1e30f, 5}, Vec3f{-7, 3, 1e20f}})
        EXPECT_FALSE(
            misses_root_box(box, Ray{org, 0.0f, {1, 0, 0}, 1.0f}, SlabTerms(org, {1, 0, 0})));
}

}  // namespace
}  // namespace rebraid
