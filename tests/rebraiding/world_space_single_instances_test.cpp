// Meshes placed by one instance, built in world space (world_space_single_instances.h): which
// meshes move, that ids and triangles stay, and what a re-braided structure makes of them.
// Hits against Embree's flat scene: accel_equivalence_test.cpp (MeshesPlacedOnceMatchEmbreeFlat
// and every shared scene).
#include "rebraid/rebraiding/world_space_single_instances.h"

#include <gtest/gtest.h>

#include <optional>

#include "rebraid/core/structure_hash.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/test_scenes.h"
#include "support/thread_count_hash.h"

namespace rebraid {
namespace {

/// Mesh 0 placed once by a rotation, mesh 1 by two instances, mesh 2 once by the identity,
/// mesh 3 once by a scale that takes its positions past the float range.
Scene mixed_placements() {
    Scene scene;
    for (std::uint64_t seed = 1; seed <= 4; ++seed)
        scene.meshes.push_back(test::make_triangle_soup(40, seed));
    Random random(3);
    scene.instances = {
        {0, test::random_transform(random, 3.0f, true)},
        {1, test::random_transform(random, 3.0f, true)},
        {1, test::random_transform(random, 3.0f, true)},
        {2, AffineTransform::identity()},
        {3, AffineTransform::scale({1e38f, 1e38f, 1e38f})},
    };
    scene.meshes[3].positions[0] = {10.0f, 0.0f, 0.0f};
    return scene;
}

TEST(WorldSpaceSingleInstances, MovesOnlyMeshesPlacedOnceByATransform) {
    const Scene scene = mixed_placements();
    const std::optional<Scene> world = single_instances_in_world_space(scene);
    ASSERT_TRUE(world.has_value());
    ASSERT_EQ(world->meshes.size(), scene.meshes.size());
    ASSERT_EQ(world->instances.size(), scene.instances.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
        EXPECT_EQ(world->instances[i].mesh_id, scene.instances[i].mesh_id) << i;
    for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
        EXPECT_EQ(world->meshes[m].triangles, scene.meshes[m].triangles) << m;
        EXPECT_EQ(world->meshes[m].name, scene.meshes[m].name) << m;
    }

    // Mesh 0: its positions mapped, its instance at the identity.
    const AffineTransform& placement = scene.instances[0].object_to_world;
    EXPECT_EQ(world->instances[0].object_to_world, AffineTransform::identity());
    ASSERT_EQ(world->meshes[0].positions.size(), scene.meshes[0].positions.size());
    for (std::size_t v = 0; v < scene.meshes[0].positions.size(); ++v) {
        const Vec3f expected = placement.transform_point(scene.meshes[0].positions[v]);
        const Vec3f got = world->meshes[0].positions[v];
        // Within rounding: the library may fuse the transform's products and sums.
        EXPECT_NEAR(got.x, expected.x, 1e-5f);
        EXPECT_NEAR(got.y, expected.y, 1e-5f);
        EXPECT_NEAR(got.z, expected.z, 1e-5f);
    }
    // Mesh 1 (shared), mesh 2 (already in world space), mesh 3 (would overflow): kept.
    for (const std::size_t i : {1u, 2u, 3u, 4u})
        EXPECT_EQ(world->instances[i].object_to_world, scene.instances[i].object_to_world) << i;
    for (const std::size_t m : {1u, 2u, 3u})
        EXPECT_EQ(world->meshes[m].positions, scene.meshes[m].positions) << m;
}

TEST(WorldSpaceSingleInstances, NothingToMoveGivesNothing) {
    // Every mesh placed several times.
    EXPECT_FALSE(single_instances_in_world_space(test::make_overlap_scene(24, 5)).has_value());
    // Placed once, by the identity or past the float range.
    Scene scene = mixed_placements();
    scene.instances = {scene.instances[3], scene.instances[4]};
    EXPECT_FALSE(single_instances_in_world_space(scene).has_value());
    EXPECT_FALSE(single_instances_in_world_space(Scene{}).has_value());
}

InstancedAccel rebraided(const Scene& scene, bool world_space) {
    RebraidSettings settings;
    settings.world_space_single_instances = world_space;
    return build_rebraid_accel(scene, own_object_bvh_builder(), settings);
}

// Each mesh placed once: in world space every item needs no ray of its own, and the top is
// merged; with object spaces kept, every instance is entered with a mapped ray.
TEST(WorldSpaceSingleInstances, ATopOfMeshesPlacedOnceIsMerged) {
    const Scene scene = test::make_overlap_scene(3, 7);
    const InstancedAccel world = rebraided(scene, true);
    const InstancedAccel object_spaces = rebraided(scene, false);
    for (const InstanceTarget& target : world.instance_targets())
        EXPECT_EQ(target.space, InstanceTarget::kWorldSpace);
    for (const InstanceTarget& target : object_spaces.instance_targets())
        EXPECT_NE(target.space, InstanceTarget::kWorldSpace);
    EXPECT_FALSE(world.merged_top_level().nodes.empty());
    EXPECT_TRUE(object_spaces.merged_top_level().nodes.empty());
    EXPECT_EQ(world.stats().instances, object_spaces.stats().instances);
    EXPECT_EQ(world.stats().triangles, object_spaces.stats().triangles);
}

TEST(WorldSpaceSingleInstances, SameStructureOnAnyThreadCount) {
    Scene scene = test::make_overlap_scene(24, 5);
    for (std::size_t i = 0; i < 6; ++i) {
        scene.meshes.push_back(scene.meshes[scene.instances[i].mesh_id]);
        scene.instances[i].mesh_id = MeshId(scene.meshes.size() - 1);
    }
    test::expect_same_hash_on_threads({1, 2, 8}, [&] {
        const InstancedAccel accel = rebraided(scene, true);
        StructureHash hash;
        hash.add_value(accel.stats().structure_hash.value());
        hash.add<WideNode>(accel.merged_top_level().nodes);
        return hash.value();
    });
}

}  // namespace
}  // namespace rebraid
