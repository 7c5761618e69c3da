// Structural guarantees of the flat and two-level structures: every triangle reachable
// exactly once, and the same structure on any thread count.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <bit>
#include <functional>

#include "rebraid/core/error.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/containment.h"
#include "support/hit_comparison.h"
#include "support/reachability.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

std::vector<test::NamedScene> all_scenes() {
    std::vector<test::NamedScene> scenes = test::generated_scenes();
    scenes.push_back({"default", make_default_scene()});
    for (const std::string& file : test::shared_scene_files())
        scenes.push_back({file, load_gltf_scene(std::string(REBRAID_SHARED_SCENES) + "/" + file)});
    return scenes;
}

TEST(FlatAccel, EveryTriangleReachableOnce) {
    for (const test::NamedScene& named : all_scenes()) {
        SCOPED_TRACE(named.name);
        test::expect_each_reached_once(test::reach_counts(named.scene, FlatAccel(named.scene)));
    }
}

TEST(TwoLevelAccel, EveryTriangleReachableOnceAndEnclosedByItsBoxes) {
    for (const test::NamedScene& named : all_scenes()) {
        SCOPED_TRACE(named.name);
        const InstancedAccel accel = build_two_level_accel(named.scene);
        test::expect_each_reached_once(test::reach_counts(named.scene, accel));
        test::expect_boxes_enclose_geometry(named.scene, accel, named.name);
    }
}

std::uint64_t hash_on(int threads, const std::function<std::uint64_t()>& build) {
    std::uint64_t hash = 0;
    tbb::task_arena arena(threads);
    arena.execute([&] { hash = build(); });
    return hash;
}

TEST(FlatAndTwoLevel, SameStructureOnOneTwoAndEightThreads) {
    tbb::global_control allow_eight(tbb::global_control::max_allowed_parallelism, 8);
    // A small threshold makes the parallel binning, partitioning and subtree paths run.
    const BuildSettings settings{.parallel_threshold = 256};
    for (const test::NamedScene& named : all_scenes()) {
        SCOPED_TRACE(named.name);
        auto flat = [&] { return *FlatAccel(named.scene, settings).stats().structure_hash; };
        auto two_level = [&] {
            return *build_two_level_accel(named.scene, own_object_bvh_builder(settings))
                        .stats()
                        .structure_hash;
        };
        for (const auto& build :
             {std::function<std::uint64_t()>(flat), std::function<std::uint64_t()>(two_level)}) {
            const std::uint64_t one = hash_on(1, build);
            EXPECT_EQ(one, hash_on(2, build));
            EXPECT_EQ(one, hash_on(8, build));
        }
    }
}

TEST(TwoLevelAccel, InstancesPlacedAlikeShareOneObjectSpace) {
    // Two meshes; instances 1 and 2 are placed by the same rotation (as a file's root node
    // places all its meshes), instance 3 by another, instance 0 by the identity.
    Scene scene;
    for (int m = 0; m < 2; ++m)
        scene.meshes.push_back(
            {"tri", {{0, 0, float(m)}, {1, 0, float(m)}, {0, 1, float(m)}}, {{0, 1, 2}}});
    const AffineTransform turn = AffineTransform::rotate({1, 0, 0}, 1.5707964f);
    const AffineTransform other = AffineTransform::translate({5, 0, 0});
    scene.instances = {{0, AffineTransform::identity()}, {0, turn}, {1, turn}, {1, other}};
    const InstancedAccel accel = build_two_level_accel(scene);
    const std::vector<InstanceTarget>& targets = accel.instance_targets();
    ASSERT_EQ(targets.size(), 4u);
    EXPECT_EQ(targets[0].space, InstanceTarget::kWorldSpace);
    EXPECT_NE(targets[1].space, InstanceTarget::kWorldSpace);
    EXPECT_EQ(targets[1].space, targets[2].space);
    EXPECT_NE(targets[3].space, InstanceTarget::kWorldSpace);
    EXPECT_NE(targets[3].space, targets[1].space);
    EXPECT_TRUE(targets[0].to_object == AffineTransform::identity());
    EXPECT_TRUE(targets[1].to_object == turn.inverse());
    EXPECT_TRUE(targets[2].to_object == turn.inverse());
    EXPECT_TRUE(targets[3].to_object == other.inverse());
    EXPECT_EQ(targets[2].mesh, 1u);
    ASSERT_EQ(accel.object_views().size(), 2u);
    EXPECT_EQ(accel.object_views()[1].nodes, accel.object_bvhs()[1].nodes.data());
    EXPECT_EQ(accel.object_views()[1].triangles, accel.object_bvhs()[1].triangles.data());
}

/// Calls check(accel, rays) for the two-level and the re-braided structure of every test
/// scene, at every kernel level this machine runs, on 2,000 varied rays of `ray_seed`.
template <class Check>
void for_each_instanced_accel_and_level(std::uint64_t ray_seed, Check&& check) {
    for (const test::NamedScene& named : all_scenes()) {
        for (bool rebraided : {false, true}) {
            InstancedAccel accel =
                rebraided ? build_rebraid_accel(named.scene) : build_two_level_accel(named.scene);
            const std::vector<Ray> rays =
                test::varied_rays(accel, named.scene.bounds(), 2000, ray_seed);
            for (SimdLevel level : runnable_simd_levels()) {
                SCOPED_TRACE(named.name + (rebraided ? " / rebraid / " : " / twolevel / ") +
                             std::string(simd_level_name(level)));
                accel.set_simd_level(level);
                check(accel, rays);
            }
        }
    }
}

bool same_corners(const TriangleVerts& a, const TriangleVerts& b) {
    return a.v0 == b.v0 && a.v1 == b.v1 && a.v2 == b.v2;
}

// intersect_located is the closest hit of intersect() and names its triangle: the leaf-order
// position whose prim_ids entry is the hit's primID, and the corners kept there (the Embree
// glue recomputes the hit's attributes from them), at every kernel level.
TEST(InstancedAccel, LocatedHitsAreTheHitsAndNameTheirTrianglesPositionAndCorners) {
    for_each_instanced_accel_and_level(
        7, [](const InstancedAccel& accel, const std::vector<Ray>& rays) {
            std::size_t hits = 0, wrong = 0;
            for (const Ray& ray : rays) {
                const Hit hit = accel.intersect(ray);
                const LocatedHit located = accel.intersect_located(ray);
                const bool same_hit = std::bit_cast<std::uint32_t>(hit.t) ==
                                          std::bit_cast<std::uint32_t>(located.hit.t) &&
                                      hit.instance_id == located.hit.instance_id &&
                                      hit.prim_id == located.hit.prim_id &&
                                      hit.u == located.hit.u && hit.v == located.hit.v;
                const HitTriangle& triangle = located.triangle;
                bool located_right = triangle.leaf_position == kInvalidId;
                if (hit.is_hit()) {
                    ++hits;
                    const ObjectBvh& bvh =
                        accel.object_bvhs()[accel.instance_meshes()[hit.instance_id]];
                    located_right =
                        triangle.leaf_position < bvh.prim_ids.size() &&
                        bvh.prim_ids[triangle.leaf_position] == hit.prim_id &&
                        same_corners(bvh.triangles[triangle.leaf_position], triangle.corners());
                }
                wrong += !(same_hit && located_right);
            }
            EXPECT_EQ(wrong, 0u);
            EXPECT_GT(hits, rays.size() / 50);  // the check saw hits
        });
}

/// What a CloserHitObserver heard: how often, and the last call's instance and triangle.
struct HeardHits {
    std::size_t calls = 0;
    InstanceId instance = kInvalidId;
    HitTriangle triangle;

    static void on_closer_hit(void* context, InstanceId instance, const HitTriangle& triangle) {
        auto& heard = *static_cast<HeardHits*>(context);
        ++heard.calls;
        heard.instance = instance;
        heard.triangle = triangle;
    }
};

// The observer of a located query hears of each closer hit as it is found; the last call
// names the closest hit's instance and triangle (the Embree glue computes the attributes it
// reports there), and a ray that hits nothing is never heard of.
TEST(InstancedAccel, ObserverHearsEveryCloserHitAndLastTheClosest) {
    for_each_instanced_accel_and_level(9, [](const InstancedAccel& accel,
                                             const std::vector<Ray>& rays) {
        std::size_t hits = 0, wrong = 0, calls = 0;
        for (const Ray& ray : rays) {
            HeardHits heard;
            const CloserHitObserver observer{&HeardHits::on_closer_hit, &heard};
            const LocatedHit located = accel.intersect_located(ray, &observer);
            const LocatedHit unobserved = accel.intersect_located(ray);
            bool right = std::bit_cast<std::uint32_t>(located.hit.t) ==
                             std::bit_cast<std::uint32_t>(unobserved.hit.t) &&
                         located.hit.prim_id == unobserved.hit.prim_id &&
                         located.hit.instance_id == unobserved.hit.instance_id;
            if (located.hit.is_hit()) {
                ++hits;
                calls += heard.calls;
                right = right && heard.calls >= 1 && heard.instance == located.hit.instance_id &&
                        heard.triangle.leaf_position == located.triangle.leaf_position &&
                        same_corners(heard.triangle.corners(), located.triangle.corners());
            } else {
                right = right && heard.calls == 0;
            }
            wrong += !right;
        }
        EXPECT_EQ(wrong, 0u);
        EXPECT_GT(hits, rays.size() / 50);
        EXPECT_GE(calls, hits);
    });
}

/// The answers of `accel` to `rays`, bit for bit: closest hit, located triangle, occlusion.
struct ExactAnswers {
    std::vector<std::uint32_t> bits;

    ExactAnswers(const InstancedAccel& accel, const std::vector<Ray>& rays) {
        for (const Ray& ray : rays) {
            const LocatedHit located = accel.intersect_located(ray);
            const Hit hit = accel.intersect(ray);
            for (const Hit& each : {located.hit, hit})
                bits.insert(bits.end(), {std::bit_cast<std::uint32_t>(each.t), each.instance_id,
                                         each.prim_id, std::bit_cast<std::uint32_t>(each.u),
                                         std::bit_cast<std::uint32_t>(each.v)});
            bits.push_back(located.triangle.leaf_position);
            const TriangleVerts corners = located.triangle.corners();
            for (const Vec3f& corner : {corners.v0, corners.v1, corners.v2})
                for (int axis = 0; axis < 3; ++axis)
                    bits.push_back(std::bit_cast<std::uint32_t>(corner[axis]));
            bits.push_back(accel.occluded(ray));
        }
    }
};

// A top level of one item takes queries of its own (the ray mapped once, no top-level
// traversal): they answer bit for bit as the general ones, made to run here by a second
// instance far away that no ray reaches, for an instance in world space and a mapped one, at
// every kernel level.
TEST(InstancedAccel, TopLevelOfOneItemAnswersAsTheGeneralTraversal) {
    for (const bool is_mapped : {false, true}) {
        SCOPED_TRACE(is_mapped ? "mapped instance" : "instance in world space");
        Scene alone;
        alone.meshes.push_back(make_torus_knot());
        alone.instances.push_back({0, is_mapped ? AffineTransform::translate({0.5f, -2.0f, 1.0f}) *
                                                      AffineTransform::rotate({1, 2, 3}, 0.7f) *
                                                      AffineTransform::scale({1.5f, 0.5f, 2.0f})
                                                : AffineTransform::identity()});
        Scene with_far = alone;
        with_far.meshes.push_back(
            {"far",
             {{1e5f, 1e5f, 1e5f}, {1e5f + 1, 1e5f, 1e5f}, {1e5f, 1e5f + 1, 1e5f}},
             {{0, 1, 2}}});
        with_far.instances.push_back({1, AffineTransform::identity()});
        InstancedAccel sole = build_two_level_accel(alone);
        InstancedAccel general = build_two_level_accel(with_far);
        ASSERT_TRUE(sole.top_level().root.is_leaf());
        ASSERT_TRUE(general.top_level().root.is_inner());
        const std::vector<Ray> rays = test::varied_rays(sole, alone.bounds(), 4000, 3);
        std::size_t hits = 0;
        for (const Ray& ray : rays) hits += sole.intersect(ray).is_hit();
        EXPECT_GT(hits, rays.size() / 50);  // the comparison sees hits
        for (SimdLevel level : runnable_simd_levels()) {
            SCOPED_TRACE(std::string(simd_level_name(level)));
            sole.set_simd_level(level);
            general.set_simd_level(level);
            EXPECT_TRUE(ExactAnswers(sole, rays).bits == ExactAnswers(general, rays).bits);
        }
    }
}

// Without the root box's test (set_culls_root_box(false), as the Embree glue runs, which
// screens rays itself) every query answers bit for bit as with it: for the two-level and the
// re-braided structures of every test scene (merged, world-tree and plain top levels among
// them), and for a top level of one item, at every kernel level.
TEST(InstancedAccel, AnswersAlikeWithAndWithoutTheRootBoxCull) {
    for_each_instanced_accel_and_level(11, [](InstancedAccel& accel, const std::vector<Ray>& rays) {
        ASSERT_TRUE(accel.culls_root_box());
        const RootBox culled = accel.root_box();
        const ExactAnswers with_cull(accel, rays);
        accel.set_culls_root_box(false);
        EXPECT_EQ(accel.root_box().lower[0], -RootBox::kInfinity);  // all of space
        EXPECT_EQ(accel.root_box().upper[2], RootBox::kInfinity);
        const bool same = ExactAnswers(accel, rays).bits == with_cull.bits;
        accel.set_culls_root_box(true);
        EXPECT_TRUE(same);
        for (int a = 0; a < 3; ++a) {  // and turned on again, the box is back
            EXPECT_EQ(accel.root_box().lower[a], culled.lower[a]);
            EXPECT_EQ(accel.root_box().upper[a], culled.upper[a]);
        }
    });
    Scene alone;
    alone.meshes.push_back(make_torus_knot());
    alone.instances.push_back({0, AffineTransform::identity()});
    InstancedAccel sole = build_two_level_accel(alone);
    ASSERT_TRUE(sole.top_level().root.is_leaf());
    ASSERT_GT(sole.root_box().upper[0], sole.root_box().lower[0]);  // a box: it does cull
    ASSERT_LT(sole.root_box().upper[0], RootBox::kInfinity);
    const std::vector<Ray> rays = test::varied_rays(sole, alone.bounds(), 4000, 5);
    const ExactAnswers with_cull(sole, rays);
    sole.set_culls_root_box(false);
    EXPECT_TRUE(ExactAnswers(sole, rays).bits == with_cull.bits);
    // The setting holds through what refreshes the sole item.
    sole.set_world_to_object(std::vector<AffineTransform>(1, AffineTransform::identity()));
    EXPECT_EQ(sole.root_box().upper[0], RootBox::kInfinity);
}

TEST(TwoLevelAccel, ManyInstancesPlacedAlikeShareTheSpaceOfTheFirst) {
    // 20,000 instances cycling through 7 placements (the identity among them): the records
    // are made in parallel, and each run of equal transforms spans many of its ranges.
    Scene scene;
    scene.meshes.push_back({"tri", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}});
    constexpr std::uint32_t kPlacements = 7;
    for (std::uint32_t i = 0; i < 20000; ++i) {
        const std::uint32_t p = (i * 3) % kPlacements;
        scene.instances.push_back(
            {0, p == 0 ? AffineTransform::identity()
                       : AffineTransform::translate({float(p), 0, 0}) *
                             AffineTransform::rotate({0, 1, 0}, 0.1f * float(p))});
    }
    const InstancedAccel accel = build_two_level_accel(scene);
    std::vector<std::uint32_t> first_of(kPlacements, kInvalidId);
    std::size_t wrong = 0;
    for (std::uint32_t i = 0; i < scene.instances.size(); ++i) {
        const std::uint32_t p = (i * 3) % kPlacements;
        if (first_of[p] == kInvalidId) first_of[p] = i;
        const std::uint32_t expected = p == 0 ? InstanceTarget::kWorldSpace : first_of[p] + 1;
        wrong += accel.instance_targets()[i].space != expected;
    }
    EXPECT_EQ(wrong, 0u);
}

TEST(TwoLevelAccel, InstanceOfAMeshWithoutObjectBvhIsRefused) {
    Scene scene;
    scene.meshes.push_back({"tri", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}});
    scene.meshes.push_back(scene.meshes[0]);
    scene.instances = {{0, AffineTransform::identity()}, {1, AffineTransform::identity()}};
    std::vector<ObjectBvh> one_bvh(1);
    EXPECT_THROW(InstancedAccel(scene, std::move(one_bvh), TopLevelBvh{}, AccelStats{}), Error);
}

}  // namespace
}  // namespace rebraid
