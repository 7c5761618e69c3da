// The world tree (world_tree.h): one BVH over every instance's triangles, built in world space,
// whose leaves keep their instance's object space. What its leaves hold, when it is built,
// that rays find what entering the instances finds (the same t to the bit), and that its tree
// is the same on any thread count. Its hits against Embree's are checked through the drop-in
// (tests/embree_glue/embree_dropin_test.cpp), whose structures trace world trees.
#include "rebraid/top_level/world_tree.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/core/structure_hash.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/entered_hits.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"
#include "support/thread_count_hash.h"

namespace rebraid {
namespace {

/// Instances crossing each other, mirrored ones among them, plus one placed by the identity
/// (its leaves tested with the world ray).
Scene crossing_scene() {
    Scene scene = test::make_overlap_scene(12, 3);
    scene.instances.push_back({MeshId(2), AffineTransform::identity()});
    return scene;
}

/// The re-braided structure of `scene`, tracing a world tree when `world_tree` (its triangle
/// budget lifted) and entering every instance otherwise.
InstancedAccel built(const Scene& scene, bool world_tree, float spatial_split_budget = 0.2f) {
    RebraidSettings settings;
    settings.world_space_single_instances = false;
    settings.world_space_copy_budget = 0.0f;
    settings.merge_world_space = false;
    settings.world_tree = world_tree;
    settings.world_tree_triangle_budget = 1e6f;
    settings.world_tree_spatial_split_budget = spatial_split_budget;
    return build_rebraid_accel(scene, own_object_bvh_builder(), settings);
}

TEST(WorldTree, LeavesHoldTheTrianglesOfOneInstanceInItsObjectSpace) {
    const Scene scene = crossing_scene();
    const InstancedAccel accel = built(scene, true);
    const MergedTopLevel& tree = accel.merged_top_level();
    ASSERT_TRUE(tree.is_world_tree);
    ASSERT_FALSE(tree.empty());
    const ObjectBvh& leaves = tree.world_tree_leaves;
    std::set<std::pair<InstanceId, PrimId>> reached;
    std::size_t leaf_count = 0;
    for (const WideNode& node : tree.nodes)
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef child = node.children[slot];
            if (!child.is_leaf() || child.is_empty()) continue;
            ++leaf_count;
            const std::uint32_t word = node.leaf_row_hints[slot];
            ASSERT_NE(word & MergedTopLevel::kSourceWordFlag, 0u);
            const MergedLeafSource& source = tree.source_named_by(word);
            EXPECT_EQ(source.target, &accel.instance_targets()[source.instance]);
            EXPECT_EQ(source.space, source.target->space);
            const Mesh& mesh = scene.meshes[scene.instances[source.instance].mesh_id];
            for (std::uint32_t i = 0; i < child.prim_count(); ++i) {
                const std::uint32_t position = child.first_prim() + i;
                const PrimId prim = leaves.prim_ids[position];
                ASSERT_LT(prim, mesh.triangles.size());
                // The mesh's own corners, not the placed ones.
                const auto corners = mesh.corners(prim);
                EXPECT_EQ(leaves.triangles[position].v0, corners[0]);
                EXPECT_EQ(leaves.triangles[position].v2, corners[2]);
                reached.insert({source.instance, prim});
            }
        }
    EXPECT_GT(leaf_count, scene.instances.size());
    // The statistics describe the tree the queries traverse.
    EXPECT_EQ(accel.stats().leaves, leaf_count);
    EXPECT_EQ(reached.size(), scene.instanced_triangle_count());
    // The instance placed by the identity is tested in world space.
    bool has_world_source = false;
    for (const MergedLeafSource& source : tree.sources)
        has_world_source |= source.space == InstanceTarget::kWorldSpace;
    EXPECT_TRUE(has_world_source);
}

TEST(WorldTree, BuiltForScenesOfAFewInstancesThatRepeatLittle) {
    const Scene scene = crossing_scene();
    TopLevelMergeSettings merge;
    EXPECT_FALSE(wants_world_tree(scene, merge));  // off unless asked
    merge.world_tree = true;
    // 13 instances of 3 meshes: far more instanced triangles than mesh triangles.
    merge.world_tree_triangle_budget = 2.0f;
    EXPECT_FALSE(wants_world_tree(scene, merge));
    merge.world_tree_triangle_budget = 10.0f;
    EXPECT_TRUE(wants_world_tree(scene, merge));
    TopLevelMergeSettings few_instances = merge;
    few_instances.world_tree_max_instances = std::uint32_t(scene.instances.size() - 1);
    EXPECT_FALSE(wants_world_tree(scene, few_instances));
    TopLevelMergeSettings few_triangles = merge;
    few_triangles.world_tree_max_triangles = scene.instanced_triangle_count() - 1;
    EXPECT_FALSE(wants_world_tree(scene, few_triangles));
    Scene single = scene;
    single.instances.resize(1);
    EXPECT_FALSE(wants_world_tree(single, merge));
    Scene each_once;
    for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
        each_once.meshes.push_back(scene.meshes[m]);
        each_once.instances.push_back({MeshId(m), scene.instances[m].object_to_world});
    }
    merge.world_tree_triangle_budget = 1.0f;
    EXPECT_TRUE(wants_world_tree(each_once, merge));
    // Through the settings: the default budget leaves the crossing scene without one.
    RebraidSettings settings;
    settings.world_tree = true;
    EXPECT_FALSE(build_rebraid_accel(scene, own_object_bvh_builder(), settings)
                     .merged_top_level()
                     .is_world_tree);
    EXPECT_TRUE(build_rebraid_accel(each_once, own_object_bvh_builder(), settings)
                    .merged_top_level()
                    .is_world_tree);
}

/// With and without spatial splits.
class WorldTreeRays : public ::testing::TestWithParam<float> {};

TEST_P(WorldTreeRays, FindWhatEnteringTheInstancesFinds) {
    const Scene scene = crossing_scene();
    InstancedAccel world = built(scene, true, GetParam());
    InstancedAccel entered = built(scene, false);
    ASSERT_TRUE(world.merged_top_level().is_world_tree);
    ASSERT_TRUE(entered.merged_top_level().empty());
    // Each triangle is tested with the ray mapped as entering its instance maps it.
    test::expect_hits_as_entering(world, entered,
                                  test::varied_rays(entered, scene.bounds(), 10000, 5), false);
}

TEST_P(WorldTreeRays, SameTreeOnAnyThreadCount) {
    const Scene scene = crossing_scene();
    const float budget = GetParam();
    test::expect_same_hash_on_threads(
        {1, 2, 8}, [&] { return built(scene, true, budget).stats().structure_hash.value(); });
}

INSTANTIATE_TEST_SUITE_P(WorldTree, WorldTreeRays, ::testing::Values(0.0f, 0.2f),
                         [](const auto& info) {
                             return std::string(info.param > 0.0f ? "SpatialSplits"
                                                                  : "ObjectSplits");
                         });

}  // namespace
}  // namespace rebraid
