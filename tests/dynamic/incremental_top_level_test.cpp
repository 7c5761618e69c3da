// The incremental top level (rebraid/dynamic/incremental_top_level.h, static_top_cut.h): after
// frames of animation it answers like Embree flat built on the deformed frame, reaches every
// triangle once, is the same on 1 and 2 threads, and really keeps the static part.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/dynamic/dynamic_scene.h"
#include "rebraid/dynamic/dynamic_scene_accel.h"
#include "rebraid/dynamic/incremental_top_level.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/generators/twisting_object.h"
#include "rebraid/io/gltf_dynamic_object.h"
#include "rebraid/io/gltf_writer.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/bvh_stats.h"
#include "support/cli_runner.h"
#include "support/containment.h"
#include "support/hit_comparison.h"
#include "support/reachability.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

constexpr int kFrameCount = 4;
constexpr float kTimeStep = 0.37f;  // not a divisor of the period: every frame differs

std::unique_ptr<AnimatedObject> small_twisting_object() {
    return make_twisting_object({.path_segment_count = 96, .tube_segment_count = 8});
}

/// Many overlapping instances, so the static top is deep enough to be cut.
Scene static_scene() {
    return test::make_overlap_scene(120, 11);
}

DynamicSceneAccelSettings incremental_settings(UpdateStrategy strategy) {
    DynamicSceneAccelSettings settings;
    settings.top = DynamicTop::rebraid_incremental;
    settings.update.strategy = strategy;
    return settings;
}

void run_frames(DynamicScene& dynamic, DynamicSceneAccel& accel, int frames) {
    for (int frame = 1; frame <= frames; ++frame) {
        dynamic.pose(static_cast<float>(frame) * kTimeStep);
        accel.update();
    }
}

void expect_matches_embree_flat(const DynamicScene& dynamic, const Accel& accel,
                                std::uint64_t seed) {
    const Scene& scene = dynamic.scene();
    const glue::EmbreeFlatAccel reference(scene);
    const std::vector<Ray> rays = test::varied_rays(reference, scene.bounds(), 10000, seed);
    test::expect_same_answers(scene, rays, test::trace_all(reference, rays),
                              test::trace_all(accel, rays), test::tolerance_for(scene.bounds()));
}

TEST(IncrementalTopLevel, MatchesEmbreeFlatOnTheDeformedFrameForEveryStrategy) {
    const auto object = small_twisting_object();
    for (UpdateStrategy strategy : kUpdateStrategies) {
        SCOPED_TRACE(std::string(update_strategy_name(strategy)));
        DynamicScene dynamic(static_scene(), *object, {.copy_count = 3});
        DynamicSceneAccel accel(dynamic, incremental_settings(strategy));
        run_frames(dynamic, accel, kFrameCount);
        expect_matches_embree_flat(dynamic, accel.accel(), 3);
    }
}

TEST(IncrementalTopLevel, MatchesEmbreeFlatWithRigidlyMovingGltfParts) {
    const std::string path = std::string(REBRAID_SHARED_SCENES) + "/motion_capture_rom.glb";
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
    const auto object = load_gltf_animated_object(path);
    DynamicScene dynamic(static_scene(), *object, {.copy_count = 2});
    ASSERT_FALSE(dynamic.moving_instances().empty());
    DynamicSceneAccel accel(dynamic, incremental_settings(UpdateStrategy::refit));
    for (int frame = 1; frame <= kFrameCount; ++frame) {
        dynamic.pose(static_cast<float>(frame) * 0.8f);
        accel.update();
    }
    expect_matches_embree_flat(dynamic, accel.accel(), 5);
    test::expect_each_reached_once(test::reach_counts(dynamic.scene(), accel.accel()));
    test::expect_boxes_enclose_geometry(dynamic.scene(), accel.accel(), "incremental top");
}

TEST(IncrementalTopLevel, ReachesEveryTriangleOnce) {
    const auto object = small_twisting_object();
    DynamicScene dynamic(static_scene(), *object, {.copy_count = 3});
    DynamicSceneAccel accel(dynamic, incremental_settings(UpdateStrategy::rebuild));
    run_frames(dynamic, accel, kFrameCount);
    test::expect_each_reached_once(test::reach_counts(dynamic.scene(), accel.accel()));
    test::expect_boxes_enclose_geometry(dynamic.scene(), accel.accel(), "incremental top");
}

std::uint64_t structure_hash_after_frames(UpdateStrategy strategy, int thread_count) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                    static_cast<std::size_t>(thread_count));
    const auto object = small_twisting_object();
    DynamicScene dynamic(static_scene(), *object, {.copy_count = 3});
    DynamicSceneAccel accel(dynamic, incremental_settings(strategy));
    run_frames(dynamic, accel, kFrameCount);
    return accel.accel().stats().structure_hash.value_or(0);
}

TEST(IncrementalTopLevel, SameStructureOnOneAndTwoThreadsAfterFrames) {
    for (UpdateStrategy strategy : {UpdateStrategy::rebuild, UpdateStrategy::rotate}) {
        SCOPED_TRACE(std::string(update_strategy_name(strategy)));
        const std::uint64_t one = structure_hash_after_frames(strategy, 1);
        EXPECT_NE(one, 0u);
        EXPECT_EQ(one, structure_hash_after_frames(strategy, 2));
    }
}

TEST(IncrementalTopLevel, BuildsTheStaticTopOnceAndKeepsItsSubtreesInPlace) {
    const auto object = small_twisting_object();
    DynamicScene dynamic(static_scene(), *object, {.copy_count = 3});
    DynamicSceneAccel accel(dynamic, incremental_settings(UpdateStrategy::refit));
    run_frames(dynamic, accel, kFrameCount);
    const IncrementalTopLevel* incremental = accel.incremental_top();
    ASSERT_NE(incremental, nullptr);
    EXPECT_EQ(incremental->static_build_count(), 1u);

    // The frame's arrays start with the static top's, bit for bit.
    const TopLevelBvh& fixed = incremental->static_top();
    const TopLevelBvh& top = accel.accel().top_level();
    ASSERT_GT(fixed.nodes.size(), 1u);
    ASSERT_GE(top.nodes.size(), fixed.nodes.size());
    EXPECT_EQ(
        std::memcmp(top.nodes.data(), fixed.nodes.data(), fixed.nodes.size() * sizeof(WideNode)),
        0);
    ASSERT_GE(top.items.size(), fixed.items.size());
    for (std::size_t i = 0; i < fixed.items.size(); ++i) {
        ASSERT_EQ(top.items[i].instance_id, fixed.items[i].instance_id) << i;
        ASSERT_EQ(top.items[i].object_node, fixed.items[i].object_node) << i;
    }
    // Whole static subtrees were kept: fewer pieces than static items, and some upper node
    // points at a static inner node.
    const IncrementalTopBuild& last = accel.last_incremental_build();
    EXPECT_FALSE(last.is_full_rebraid);
    EXPECT_GT(last.cut_pieces, 0u);
    EXPECT_LT(last.cut_pieces, fixed.items.size());
    EXPECT_EQ(last.brefs, fixed.items.size() + last.dynamic_brefs);
    bool has_kept_subtree = false;
    for (std::size_t n = fixed.nodes.size(); n < top.nodes.size(); ++n)
        for (NodeRef child : top.nodes[n].children)
            has_kept_subtree |= child.is_inner() && child.node_id() < fixed.nodes.size();
    EXPECT_TRUE(has_kept_subtree);
}

/// SAH of `top` over the scene's instances and these object BVHs.
double sah_of(const Scene& scene, const std::vector<ObjectBvh>& object_bvhs,
              const TopLevelBvh& top) {
    std::vector<std::uint32_t> meshes;
    std::vector<AffineTransform> transforms;
    for (const Instance& instance : scene.instances) {
        meshes.push_back(instance.mesh_id);
        transforms.push_back(instance.object_to_world);
    }
    return top_level_sah(top, object_bvhs, meshes, transforms);
}

TEST(IncrementalTopLevel, SahStaysCloseToAFullRebraid) {
    const auto object = small_twisting_object();
    DynamicScene dynamic(static_scene(), *object, {.copy_count = 3});
    DynamicSceneAccel accel(dynamic, incremental_settings(UpdateStrategy::rebuild));
    run_frames(dynamic, accel, kFrameCount);
    const Scene& scene = dynamic.scene();
    const std::vector<ObjectBvh>& object_bvhs = accel.accel().object_bvhs();
    const double incremental = sah_of(scene, object_bvhs, accel.accel().top_level());
    const double full = sah_of(scene, object_bvhs, build_rebraid(scene, object_bvhs).top);
    // A loose bound: the point is that grafting keeps the quality of re-braiding, not its
    // digits (on this scene the two are within 1%).
    EXPECT_LT(incremental, 1.1 * full);
}

TEST(IncrementalTopLevel, StaticTopGetsTheBudgetOfTheWholeScene) {
    const Scene scene = static_scene();
    const std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    std::vector<InstanceId> static_ids, dynamic_ids;
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
        (i % 4 == 0 ? dynamic_ids : static_ids).push_back(InstanceId(i));
    // The rule's budget, without the search's doublings, which depend on what each build
    // opens.
    const RebraidSettings rule_budget{.budget_doublings = 0};
    const std::uint64_t full_budget = build_rebraid(scene, object_bvhs, rule_budget).budget;
    const std::uint64_t dynamic_budget =
        build_rebraid(scene, object_bvhs, rule_budget, dynamic_ids).budget;
    for (bool whole_scene : {true, false}) {
        IncrementalTopLevel incremental(rule_budget,
                                        {.static_budget_for_whole_scene = whole_scene});
        incremental.build_static(scene, object_bvhs, static_ids);
        const std::uint64_t static_budget =
            incremental.build_frame(scene, object_bvhs, dynamic_ids).budget - dynamic_budget;
        if (whole_scene)  // up to the rounding of the scaled budget factor
            EXPECT_NEAR(double(static_budget), double(full_budget), 1.0);
        else
            EXPECT_LT(static_budget, full_budget);
    }
}

TEST(IncrementalTopLevel, WithoutDynamicInstancesTheFrameIsTheStaticTop) {
    const Scene scene = static_scene();
    const std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    std::vector<InstanceId> every(scene.instances.size());
    for (std::size_t i = 0; i < every.size(); ++i) every[i] = InstanceId(i);
    IncrementalTopLevel incremental;
    incremental.build_static(scene, object_bvhs, every);
    const IncrementalTopBuild frame = incremental.build_frame(scene, object_bvhs, {});
    EXPECT_EQ(frame.top.root, incremental.static_top().root);
    EXPECT_EQ(frame.cut_pieces, 1u);
    EXPECT_EQ(frame.top.items.size(), incremental.static_top().items.size());
}

TEST(IncrementalTopLevel, RejectsAFrameBeforeTheStaticBuildAndStaticDynamicInstances) {
    const Scene scene = static_scene();
    const std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    IncrementalTopLevel incremental;
    const std::vector<InstanceId> first{0, 1, 2};
    EXPECT_THROW(incremental.build_frame(scene, object_bvhs, first), Error);
    incremental.build_static(scene, object_bvhs, first);
    const std::vector<InstanceId> overlapping{2, 3};
    EXPECT_THROW(incremental.build_frame(scene, object_bvhs, overlapping), Error);
    const std::vector<InstanceId> past_end{InstanceId(scene.instances.size())};
    EXPECT_THROW(incremental.build_frame(scene, object_bvhs, past_end), Error);
    EXPECT_THROW(IncrementalTopLevel({}, {.max_cut_pieces = 0}), Error);
}

/// True when the two tops have the same arrays, bit for bit.
bool same_top(const TopLevelBvh& a, const TopLevelBvh& b) {
    if (a.nodes.size() != b.nodes.size() || a.items.size() != b.items.size() ||
        a.item_bounds != b.item_bounds || a.root != b.root || !(a.bounds == b.bounds))
        return false;
    for (std::size_t i = 0; i < a.items.size(); ++i)
        if (a.items[i].instance_id != b.items[i].instance_id ||
            a.items[i].object_node != b.items[i].object_node)
            return false;
    return std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(WideNode)) == 0;
}

TEST(IncrementalTopLevel, ReusingThePreviousTopGivesTheSameFrame) {
    const auto object = small_twisting_object();
    DynamicScene dynamic(static_scene(), *object, {.copy_count = 3});
    const Scene& scene = dynamic.scene();
    std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    std::vector<InstanceId> static_ids;
    for (std::size_t i = 0; i < dynamic.static_instance_count(); ++i)
        static_ids.push_back(InstanceId(i));
    IncrementalTopLevel incremental;
    incremental.build_static(scene, object_bvhs, static_ids);
    const std::vector<InstanceId>& changing = dynamic.changing_instances();
    TopLevelBvh previous;  // empty on the first frame: the static top is copied
    for (int frame = 1; frame <= kFrameCount; ++frame) {
        dynamic.pose(static_cast<float>(frame) * kTimeStep);
        for (MeshId mesh_id : dynamic.dynamic_meshes())
            object_bvhs[mesh_id] = build_object_bvh(scene.meshes[mesh_id]);
        const IncrementalTopBuild fresh = incremental.build_frame(scene, object_bvhs, changing);
        IncrementalTopBuild reused =
            incremental.build_frame(scene, object_bvhs, changing, std::move(previous));
        ASSERT_FALSE(fresh.is_full_rebraid);
        EXPECT_TRUE(same_top(fresh.top, reused.top)) << "frame " << frame;
        EXPECT_EQ(fresh.brefs, reused.brefs);
        previous = std::move(reused.top);
    }
    // A top that does not start with the static one is refused.
    TopLevelBvh other = build_rebraid(scene, object_bvhs).top;
    other.nodes.resize(incremental.static_top().nodes.size() + 1, other.nodes.front());
    other.items.resize(incremental.static_top().items.size() + 1, other.items.front());
    other.item_bounds.resize(other.items.size(), other.item_bounds.front());
    EXPECT_THROW(incremental.build_frame(scene, object_bvhs, changing, std::move(other)), Error);
    TopLevelBvh shorter = incremental.static_top();
    shorter.nodes.pop_back();
    EXPECT_THROW(incremental.build_frame(scene, object_bvhs, changing, std::move(shorter)), Error);
}

TEST(StaticTopCut, OpensOnlyWhereDynamicBoxesOverlapAndWithinTheLimit) {
    const Scene scene = static_scene();
    const std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    const TopLevelBvh fixed = build_rebraid(scene, object_bvhs).top;
    ASSERT_TRUE(fixed.root.is_inner());
    // A dynamic top far outside the static one overlaps nothing: the root stays whole.
    TopLevelBvh far_away;
    far_away.root = NodeRef::leaf(0, 1);
    far_away.bounds = {fixed.bounds.max + Vec3f{1, 1, 1}, fixed.bounds.max + Vec3f{2, 2, 2}};
    EXPECT_EQ(cut_static_top(fixed, far_away, 4096).pieces.size(), 1u);
    // One covering everything opens down to the items, unless the limit stops it.
    TopLevelBvh everywhere = far_away;
    everywhere.bounds = fixed.bounds;
    const StaticTopCut full = cut_static_top(fixed, everywhere, 1u << 20);
    EXPECT_EQ(full.pieces.size(), fixed.items.size());
    for (const StaticTopPiece& piece : full.pieces) EXPECT_TRUE(piece.ref.is_leaf());
    const StaticTopCut limited = cut_static_top(fixed, everywhere, 20);
    EXPECT_LE(limited.pieces.size(), 20u);
    EXPECT_GT(limited.pieces.size(), 1u);
}

TEST(AnimateCommand, RebraidIncrementalTopIsAMethodOfItsOwn) {
    const std::filesystem::path dir = test::test_scratch_dir("incremental", true);
    const std::string static_path = (dir / "static.glb").string();
    write_gltf_scene(test::make_overlap_scene(20, 3), static_path);
    const test::CommandResult result = test::run_rebraid_in(
        dir, {"animate", "--static", static_path, "--frames", "2", "--copies", "2", "--width", "16",
              "--height", "9", "--no-embree", "--top", "rebraid,rebraid-incremental", "--update",
              "refit", "--max-cut", "64", "--json"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json json = nlohmann::json::parse(result.out);
    ASSERT_EQ(json.size(), 2u);
    EXPECT_EQ(json[0]["method"], "rebraid+refit");
    EXPECT_EQ(json[1]["method"], "rebraid-incremental+refit");
    EXPECT_GE(json[1]["final_sah"].get<double>(), 1.0);
}

}  // namespace
}  // namespace rebraid
