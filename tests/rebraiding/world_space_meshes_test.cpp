// Meshes built in world space (world_space_meshes.h): which meshes move or are copied, that
// instance ids and triangles stay, and what a re-braided structure makes of them.
// Hits against Embree's flat scene: accel_equivalence_test.cpp (MeshesPlacedOnceMatchEmbreeFlat
// and every shared scene).
#include "rebraid/rebraiding/world_space_meshes.h"

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

/// Expects `world`'s instance `i` to place, by the identity, `scene`'s instance i's triangles
/// mapped into world space.
void expect_placed_in_world_space(const Scene& scene, const Scene& world, std::size_t i) {
    const Instance& original = scene.instances[i];
    const Instance& moved = world.instances[i];
    EXPECT_EQ(moved.object_to_world, AffineTransform::identity()) << i;
    const Mesh& source = scene.meshes[original.mesh_id];
    const Mesh& copy = world.meshes[moved.mesh_id];
    EXPECT_EQ(copy.triangles, source.triangles) << i;
    ASSERT_EQ(copy.positions.size(), source.positions.size()) << i;
    for (std::size_t v = 0; v < source.positions.size(); ++v) {
        const Vec3f expected = original.object_to_world.transform_point(source.positions[v]);
        // Within rounding: the library may fuse the transform's products and sums.
        EXPECT_NEAR(copy.positions[v].x, expected.x, 1e-5f);
        EXPECT_NEAR(copy.positions[v].y, expected.y, 1e-5f);
        EXPECT_NEAR(copy.positions[v].z, expected.z, 1e-5f);
    }
}

TEST(WorldSpaceMeshes, MovesOnlyMeshesPlacedOnceByATransform) {
    const Scene scene = mixed_placements();
    const std::optional<Scene> world = meshes_in_world_space(scene, {});
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
    expect_placed_in_world_space(scene, *world, 0);
    // Mesh 1 (shared), mesh 2 (already in world space), mesh 3 (would overflow): kept.
    for (const std::size_t i : {1u, 2u, 3u, 4u})
        EXPECT_EQ(world->instances[i].object_to_world, scene.instances[i].object_to_world) << i;
    for (const std::size_t m : {1u, 2u, 3u})
        EXPECT_EQ(world->meshes[m].positions, scene.meshes[m].positions) << m;
}

TEST(WorldSpaceMeshes, NothingToMoveGivesNothing) {
    // Every mesh placed several times.
    EXPECT_FALSE(meshes_in_world_space(test::make_overlap_scene(24, 5), {}).has_value());
    // Placed once, by the identity or past the float range.
    Scene scene = mixed_placements();
    scene.instances = {scene.instances[3], scene.instances[4]};
    EXPECT_FALSE(meshes_in_world_space(scene, {}).has_value());
    EXPECT_FALSE(meshes_in_world_space(Scene{}, {}).has_value());
    // Asked for nothing.
    EXPECT_FALSE(meshes_in_world_space(mixed_placements(), {.single_instances = false}));
}

TEST(WorldSpaceMeshes, CopiesSharedMeshesWithinTheBudgetFewestTrianglesFirst) {
    // Mesh 0: 40 triangles placed twice (adds 40), mesh 1: 60 placed three times (adds 120),
    // mesh 2: 10 placed once. 110 mesh triangles (instanced: 270).
    Scene scene;
    scene.meshes = {test::make_triangle_soup(40, 1), test::make_triangle_soup(60, 2),
                    test::make_triangle_soup(10, 3)};
    Random random(5);
    for (const MeshId mesh : {1u, 0u, 1u, 2u, 0u, 1u})
        scene.instances.push_back({mesh, test::random_transform(random, 3.0f, true)});
    // 0.4 of 110 is 44: mesh 0's copy fits, mesh 1's do not.
    const std::optional<Scene> world =
        meshes_in_world_space(scene, {.single_instances = true, .copy_budget = 0.4f});
    ASSERT_TRUE(world.has_value());
    ASSERT_EQ(world->instances.size(), scene.instances.size());
    // Mesh 0's first instance (1) takes its place, its second (4) a copy after the meshes.
    ASSERT_EQ(world->meshes.size(), 4u);
    EXPECT_EQ(world->instances[1].mesh_id, 0u);
    EXPECT_EQ(world->instances[4].mesh_id, 3u);
    for (const std::size_t i : {1u, 3u, 4u}) expect_placed_in_world_space(scene, *world, i);
    for (const std::size_t i : {0u, 2u, 5u}) {
        EXPECT_EQ(world->instances[i].mesh_id, scene.instances[i].mesh_id) << i;
        EXPECT_EQ(world->instances[i].object_to_world, scene.instances[i].object_to_world) << i;
    }
    EXPECT_EQ(world->meshes[1].positions, scene.meshes[1].positions);
    // Enough for both (160 added triangles): every instance in world space, one mesh each.
    const std::optional<Scene> all =
        meshes_in_world_space(scene, {.single_instances = true, .copy_budget = 1.5f});
    ASSERT_TRUE(all.has_value());
    EXPECT_EQ(all->meshes.size(), scene.instances.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
        expect_placed_in_world_space(scene, *all, i);
    // Copies only: the mesh placed once keeps its space.
    const std::optional<Scene> copies =
        meshes_in_world_space(scene, {.single_instances = false, .copy_budget = 1.5f});
    ASSERT_TRUE(copies.has_value());
    EXPECT_EQ(copies->instances[3].object_to_world, scene.instances[3].object_to_world);
    EXPECT_EQ(copies->meshes[2].positions, scene.meshes[2].positions);
}

InstancedAccel rebraided(const Scene& scene, bool world_space) {
    RebraidSettings settings;
    settings.world_space_single_instances = world_space;
    return build_rebraid_accel(scene, own_object_bvh_builder(), settings);
}

// Each mesh placed once: in world space every item needs no ray of its own, and the top is
// merged; with object spaces kept, every instance is entered with a mapped ray.
TEST(WorldSpaceMeshes, ATopOfMeshesPlacedOnceIsMerged) {
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

TEST(WorldSpaceMeshes, SameStructureOnAnyThreadCount) {
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
