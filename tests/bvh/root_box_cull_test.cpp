// Compiled with the library's kernel flags (AVX2 + FMA where the build has them), so that the
// cull and the node test below are the kernels' own.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "rebraid/bvh/node_box_test.h"
#include "rebraid/bvh/root_box.h"
#include "rebraid/bvh/root_box_cull.h"
#include "rebraid/bvh/traversal_ray.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/ray.h"

namespace rebraid {
namespace {

/// A root node of `count` random child boxes inside [-2, 2]^3 (some of them flat).
std::vector<WideNode> random_root(std::mt19937& random, int count) {
    std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
    std::vector<WideNode> nodes(1, WideNode::make_empty());
    for (int slot = 0; slot < count; ++slot) {
        BBox3f box;
        box.extend(Vec3f{coordinate(random), coordinate(random), coordinate(random)});
        Vec3f corner{coordinate(random), coordinate(random), coordinate(random)};
        if (slot % 3 == 2) corner.y = box.min.y;  // a flat box, as a single planar triangle's
        box.extend(corner);
        nodes[0].set_child(slot, NodeRef::leaf(std::uint32_t(slot), 1), box);
    }
    return nodes;
}

/// Rays of every kind the cull must not get wrong: from anywhere near or far, aimed at the
/// children's corners and faces (the union box's planes are theirs), along the union box's
/// planes, with axis-parallel directions, and with intervals that end at, before or past it.
std::vector<Ray> rays_around(std::mt19937& random, const WideNode& root) {
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::uniform_real_distribution<float> fraction(0.0f, 1.0f);
    const BBox3f bounds = root.bounds();
    std::vector<Ray> rays;
    const auto origin_outside = [&](float distance) {
        Vec3f org{unit(random), unit(random), unit(random)};
        return org * (distance / std::max(1e-3f, length(org)));
    };
    for (int i = 0; i < 400; ++i) {
        const float distance = i % 4 == 0 ? 1e5f : 2.0f + 6.0f * fraction(random);
        const Vec3f org = origin_outside(distance);
        // At a corner of a child box, or at a point on one of its faces.
        const BBox3f child = root.child_bounds(i % root.child_count());
        Vec3f target{i & 1 ? child.max.x : child.min.x, i & 2 ? child.max.y : child.min.y,
                     i & 4 ? child.max.z : child.min.z};
        if (i % 5 == 0) target.x = child.min.x + fraction(random) * (child.max.x - child.min.x);
        Vec3f dir = target - org;
        if (i % 7 == 0) dir.y = 0.0f;  // parallel to the y planes
        if (i % 11 == 0) dir = {0.0f, 0.0f, target.z > org.z ? 1.0f : -1.0f};
        Ray ray{org, 0.0f, dir, std::numeric_limits<float>::infinity()};
        rays.push_back(ray);
        ray.tfar = 1.0f;  // ends at the target (dir is unnormalised)
        rays.push_back(ray);
        ray.tfar = std::nextafter(1.0f, 0.0f);
        rays.push_back(ray);
        ray.tnear = 1.0f;
        ray.tfar = std::numeric_limits<float>::infinity();
        rays.push_back(ray);
        ray.tnear = 2.0f;
        ray.tfar = 1.0f;  // an empty interval
        rays.push_back(ray);
    }
    // Along the union box's own planes, from outside it.
    for (int i = 0; i < 200; ++i) {
        const int axis = i % 3;
        Vec3f org = origin_outside(3.0f + fraction(random));
        org[axis] = i & 8 ? bounds.max[axis] : bounds.min[axis];
        Vec3f dir = Vec3f{unit(random), unit(random), unit(random)} * 0.5f - org * 0.1f;
        dir[axis] = 0.0f;
        rays.push_back(Ray{org, 0.0f, dir, std::numeric_limits<float>::infinity()});
    }
    // From inside the union box, and from anywhere in any direction.
    for (int i = 0; i < 400; ++i) {
        const Vec3f org = i % 2 ? bounds.center() + Vec3f{unit(random), unit(random), unit(random)}
                                : Vec3f{unit(random), unit(random), unit(random)} * 8.0f;
        rays.push_back(
            Ray{org, 0.0f, {unit(random), unit(random), unit(random)}, 20.0f * fraction(random)});
    }
    return rays;
}

/// Whether the slab test of NodeBoxTest, in float arithmetic, lets the ray into `child`: the
/// same reciprocals and robust multipliers, float max and min. (NodeBoxTest takes max and min
/// on the floats' bits, which lets in a few rays more that meet no box.)
bool enters(const TraversalRay& ray, const BBox3f& child) {
    float entry = ray.tnear, exit = ray.tfar * kRobustBoxScale;
    for (int a = 0; a < 3; ++a) {
        const bool negative = (ray.negative_axes >> a) & 1u;
        const float negated = -ray.rdir[a];
        const float far_negated =
            std::bit_cast<float>(std::bit_cast<std::uint32_t>(negated * kRobustBoxScale) + 1u);
        const float near_plane = negative ? child.max[a] : child.min[a];
        const float far_plane = negative ? child.min[a] : child.max[a];
        entry = std::max(entry, (ray.org[a] - near_plane) * negated);
        exit = std::min(exit, (ray.org[a] - far_plane) * far_negated);
    }
    return entry <= exit;
}

TEST(RootBoxCull, NeverRejectsARayTheRootsSlabTestLetsIntoAChild) {
    std::mt19937 random(20261206);
    std::size_t rejected = 0, entered = 0;
    for (int scene = 0; scene < 200; ++scene) {
        const std::vector<WideNode> nodes = random_root(random, 1 + scene % 8);
        const RootBox box = root_box_of(nodes, NodeRef::inner(0));
        for (const Ray& ray : rays_around(random, nodes[0])) {
            const TraversalRay prepared(ray.org, ray.dir, ray.tnear, ray.tfar);
            bool any_child = false;
            for (int c = 0; c < nodes[0].child_count(); ++c)
                any_child = any_child || enters(prepared, nodes[0].child_bounds(c));
            const bool misses = misses_root_box(box, ray, DirectionReciprocals(ray.dir));
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

TEST(RootBoxCull, RejectsNothingWhereTheRootIsALeaf) {
    const std::vector<WideNode> nodes(1, WideNode::make_empty());
    const RootBox box = root_box_of(nodes, NodeRef::leaf(0, 3));
    for (const Vec3f org : {Vec3f{0, 0, 0}, Vec3f{1e30f, -1e30f, 5}, Vec3f{-7, 3, 1e20f}})
        EXPECT_FALSE(
            misses_root_box(box, Ray{org, 0.0f, {1, 0, 0}, 1.0f}, DirectionReciprocals({1, 0, 0})));
}

}  // namespace
}  // namespace rebraid
