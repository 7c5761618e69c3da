#include "rebraid/generators/random_rays.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "rebraid/core/random.h"

namespace rebraid {
namespace {

const BBox3f kBounds{{-2.0f, 0.0f, 10.0f}, {6.0f, 1.0f, 14.0f}};

bool same_bits(const Ray& a, const Ray& b) {
    auto bits = [](float f) { return std::bit_cast<std::uint32_t>(f); };
    for (int axis = 0; axis < 3; ++axis)
        if (bits(a.org[axis]) != bits(b.org[axis]) || bits(a.dir[axis]) != bits(b.dir[axis]))
            return false;
    return bits(a.tnear) == bits(b.tnear) && bits(a.tfar) == bits(b.tfar);
}

TEST(RandomRays, SameSeedGivesIdenticalRays) {
    const auto a = generate_random_rays(kBounds, 5000, 42);
    const auto b = generate_random_rays(kBounds, 5000, 42);
    ASSERT_EQ(a.size(), 5000u);
    ASSERT_EQ(b.size(), a.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(same_bits(a[i], b[i])) << i;
}

TEST(RandomRays, DifferentSeedsGiveDifferentRays) {
    const auto a = generate_random_rays(kBounds, 1000, 1);
    const auto b = generate_random_rays(kBounds, 1000, 2);
    std::size_t equal_count = 0;
    for (std::size_t i = 0; i < a.size(); ++i) equal_count += same_bits(a[i], b[i]) ? 1 : 0;
    EXPECT_EQ(equal_count, 0u);
}

TEST(RandomRays, ShorterRequestIsPrefixOfLonger) {
    const auto short_run = generate_random_rays(kBounds, 10, 9);
    const auto long_run = generate_random_rays(kBounds, 100, 9);
    for (std::size_t i = 0; i < short_run.size(); ++i)
        EXPECT_TRUE(same_bits(short_run[i], long_run[i])) << i;
}

TEST(RandomRays, OriginsFillTheGrownBoxAndDirectionsAreUnit) {
    const auto rays = generate_random_rays(kBounds, 20000, 3);
    const Vec3f margin = kBounds.extent() * 0.25f;
    const BBox3f grown{kBounds.min - margin, kBounds.max + margin};
    BBox3f seen;
    Vec3f direction_sum;
    std::size_t outside_original = 0;
    for (const Ray& ray : rays) {
        EXPECT_TRUE(grown.contains({ray.org, ray.org})) << ray.org.x << " " << ray.org.y;
        EXPECT_NEAR(length(ray.dir), 1.0f, 1e-5f);
        EXPECT_EQ(ray.tnear, 0.0f);
        EXPECT_EQ(ray.tfar, std::numeric_limits<float>::infinity());
        seen.extend(ray.org);
        direction_sum = direction_sum + ray.dir;
        outside_original += kBounds.contains({ray.org, ray.org}) ? 0 : 1;
    }
    // Origins reach near every face of the grown box, and some lie outside the original.
    for (int axis = 0; axis < 3; ++axis) {
        const float tolerance = 0.02f * (grown.max[axis] - grown.min[axis]);
        EXPECT_NEAR(seen.min[axis], grown.min[axis], tolerance);
        EXPECT_NEAR(seen.max[axis], grown.max[axis], tolerance);
    }
    EXPECT_GT(outside_original, rays.size() / 4);
    // Uniform directions average to ~0 (standard error per axis ~ 0.004 here).
    EXPECT_LT(length(direction_sum / static_cast<float>(rays.size())), 0.03f);
}

TEST(RandomRays, DirectionsCoverEveryOctantEvenly) {
    const auto rays = generate_random_rays(kBounds, 40000, 8);
    std::size_t octant_counts[8] = {};
    for (const Ray& ray : rays)
        ++octant_counts[(ray.dir.x > 0 ? 1 : 0) + (ray.dir.y > 0 ? 2 : 0) +
                        (ray.dir.z > 0 ? 4 : 0)];
    // Expected 5000 each; binomial standard deviation ~66.
    for (std::size_t count : octant_counts) EXPECT_NEAR(static_cast<double>(count), 5000.0, 400.0);
}

TEST(RandomRays, DegenerateBoxesStillGiveValidRays) {
    const BBox3f flat{{0.0f, 3.0f, 0.0f}, {10.0f, 3.0f, 10.0f}};
    const BBox3f point{{1.0f, 2.0f, 3.0f}, {1.0f, 2.0f, 3.0f}};
    const BBox3f empty{};
    for (const BBox3f& box : {flat, point, empty}) {
        const auto rays = generate_random_rays(box, 500, 4);
        ASSERT_EQ(rays.size(), 500u);
        BBox3f seen;
        for (const Ray& ray : rays) {
            EXPECT_TRUE(is_finite(ray.org));
            EXPECT_NEAR(length(ray.dir), 1.0f, 1e-5f);
            seen.extend(ray.org);
        }
        // A padded axis spreads origins instead of collapsing them onto one value.
        for (int axis = 0; axis < 3; ++axis) EXPECT_GT(seen.max[axis] - seen.min[axis], 0.5f);
    }
    const auto flat_rays = generate_random_rays(flat, 500, 4);
    for (const Ray& ray : flat_rays) {
        EXPECT_GE(ray.org.y, 2.0f);
        EXPECT_LE(ray.org.y, 4.0f);
    }
}

TEST(RandomRays, ZeroCountGivesNoRays) {
    EXPECT_TRUE(generate_random_rays(kBounds, 0, 1).empty());
}

TEST(Random, FloatsStayInUnitIntervalAndLookUniform) {
    Random random(123);
    double sum = 0.0;
    float lowest = 1.0f, highest = 0.0f;
    constexpr int kCount = 100000;
    for (int i = 0; i < kCount; ++i) {
        const float f = random.next_float01();
        ASSERT_GE(f, 0.0f);
        ASSERT_LT(f, 1.0f);
        sum += f;
        lowest = std::fmin(lowest, f);
        highest = std::fmax(highest, f);
    }
    EXPECT_NEAR(sum / kCount, 0.5, 0.005);  // standard error ~0.0009
    EXPECT_LT(lowest, 0.001f);
    EXPECT_GT(highest, 0.999f);
}

TEST(Random, NextBelowStaysBelowBoundAndHitsEveryValue) {
    Random random(77);
    int counts[7] = {};
    for (int i = 0; i < 7000; ++i) {
        const std::uint32_t v = random.next_below(7);
        ASSERT_LT(v, 7u);
        ++counts[v];
    }
    for (int count : counts) EXPECT_NEAR(count, 1000, 150);
}

TEST(Random, NearbySeedsGiveUnrelatedStreams) {
    Random a(1000), b(1001);
    int equal_count = 0;
    for (int i = 0; i < 1000; ++i) equal_count += a.next_u32() == b.next_u32() ? 1 : 0;
    EXPECT_LT(equal_count, 3);
}

}  // namespace
}  // namespace rebraid
