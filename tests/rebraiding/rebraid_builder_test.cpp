#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/rebraiding/rebraid_accel.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cstdint>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/top_level/two_level_builder.h"
#include "support/containment.h"
#include "support/hit_comparison.h"
#include "support/reachability.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"
#include "support/thread_count_hash.h"

namespace rebraid {
namespace {

struct NamedSettings {
    std::string name;
    RebraidSettings settings;
};

/// The paper's rules (RebraidSettings::paper_rules) with `change` applied.
template <class Change>
RebraidSettings paper_with(Change change) {
    RebraidSettings settings = RebraidSettings::paper_rules();
    change(settings);
    return settings;
}

/// The paper's rules: as published, plain two-level (no budget), open everything (huge
/// budget, no threshold), a high threshold, the per-primitive budget rule and the tighter
/// BRef bounds rule; and the project's defaults (sah opening, vertex bounds).
std::vector<NamedSettings> settings_variants() {
    return {
        {"paper", RebraidSettings::paper_rules()},
        {"no-budget", paper_with([](RebraidSettings& s) {
             s.budget_rule = BudgetRule::per_instance;
             s.budget_factor = 0.0f;
         })},
        {"open-everything", paper_with([](RebraidSettings& s) {
             s.open_threshold = 0.0f;
             s.budget_factor = 1000.0f;
         })},
        {"threshold-0.5", paper_with([](RebraidSettings& s) {
             s.open_threshold = 0.5f;
             s.budget_factor = 2.0f;
         })},
        {"per-primitive", paper_with([](RebraidSettings& s) {
             s.budget_rule = BudgetRule::per_primitive;
             s.primitives_per_bref = 100.0f;
         })},
        {"children-bounds", paper_with([](RebraidSettings& s) {
             s.open_threshold = 0.05f;
             s.budget_factor = 8.0f;
             s.bounds_rule = BRefBoundsRule::transformed_children;
         })},
        {"default", {}},
        {"tree-as-opened",
         [] {
             RebraidSettings settings;
             settings.rebuild_tree = false;  // the tree grown while opening
             return settings;
         }()},
        {"rebuilt-greedy",
         [] {
             RebraidSettings settings;
             settings.build.collapse = NodeCollapse::greedy;  // the default cut is optimal
             return settings;
         }()},
        {"default-tables",
         [] {
             RebraidSettings settings;
             settings.support_table_instances = 1;  // every mesh's BRefs from support tables
             return settings;
         }()},
    };
}

std::vector<test::NamedScene> rebraid_scenes() {
    std::vector<test::NamedScene> scenes = test::generated_scenes();
    scenes.push_back({"default", make_default_scene()});
    return scenes;
}

TEST(RebraidBuilder, MatchesEmbreeFlatAtSeveralSettings) {
    for (const test::NamedScene& named : rebraid_scenes()) {
        const glue::EmbreeFlatAccel reference(named.scene);
        const std::vector<Ray> rays = test::varied_rays(reference, named.scene.bounds(), 10000, 7);
        const test::AccelAnswers expected = test::trace_all(reference, rays);
        const std::vector<ObjectBvh> bvhs =
            build_object_bvhs(named.scene, own_object_bvh_builder());
        for (const NamedSettings& variant : settings_variants()) {
            SCOPED_TRACE(named.name + " / " + variant.name);
            RebraidBuild build = build_rebraid(named.scene, bvhs, variant.settings);
            const InstancedAccel accel(named.scene, bvhs, std::move(build.top), {});
            test::expect_same_answers(named.scene, rays, expected, test::trace_all(accel, rays),
                                      test::tolerance_for(named.scene.bounds()));
        }
    }
}

TEST(RebraidBuilder, EveryTriangleReachableOnceAndBudgetKept) {
    for (const test::NamedScene& named : rebraid_scenes()) {
        const std::vector<ObjectBvh> bvhs =
            build_object_bvhs(named.scene, own_object_bvh_builder());
        for (const NamedSettings& variant : settings_variants()) {
            SCOPED_TRACE(named.name + " / " + variant.name);
            RebraidBuild build = build_rebraid(named.scene, bvhs, variant.settings);
            const std::uint64_t instances = named.scene.instances.size();
            EXPECT_LE(build.brefs, instances + build.budget);
            EXPECT_EQ(build.top.items.size(), build.brefs);
            if (variant.settings.budget_factor == 0.0f &&
                variant.settings.budget_rule == BudgetRule::per_instance) {
                EXPECT_EQ(build.budget, 0u);
                EXPECT_EQ(build.opened, 0u);
                EXPECT_EQ(build.brefs, instances);
            }
            const InstancedAccel accel(named.scene, bvhs, std::move(build.top), {});
            test::expect_each_reached_once(test::reach_counts(named.scene, accel));
            test::expect_boxes_enclose_geometry(named.scene, accel, named.name);
        }
    }
}

TEST(RebraidBuilder, OpensWhereInstancesOverlap) {
    const Scene scene = test::make_overlap_scene(200, 3);
    const std::vector<ObjectBvh> bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    const RebraidBuild build = build_rebraid(scene, bvhs, {});
    EXPECT_GT(build.opened, 0u);
    EXPECT_GT(build.brefs, scene.instances.size());
    EXPECT_EQ(build.budget, 4u * scene.instances.size());
}

TEST(RebraidBuilder, NoBudgetGivesAPlainTwoLevelTop) {
    const Scene scene = make_default_scene();
    const std::vector<ObjectBvh> bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    // The paper's rules, whose BRef boxes are the plain top's (transformed node boxes).
    RebraidSettings no_budget = RebraidSettings::paper_rules();
    no_budget.budget_rule = BudgetRule::per_instance;
    no_budget.budget_factor = 0.0f;
    RebraidBuild rebraided = build_rebraid(scene, bvhs, no_budget);
    // Without budget nothing opens: one item per instance, at its object root.
    ASSERT_EQ(rebraided.top.items.size(), scene.instances.size());
    std::vector<int> seen(scene.instances.size(), 0);
    for (const TopLevelItem& item : rebraided.top.items) {
        ++seen[item.instance_id];
        EXPECT_EQ(item.object_node, bvhs[scene.instances[item.instance_id].mesh_id].root);
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(seen.size()));
    // The plain builder partitions the same items with its own split search (tiny ranges are
    // split exhaustively there): the two tops may differ, their SAH barely.
    TopLevelBvh plain = build_two_level(scene, bvhs);
    const InstancedAccel a(scene, bvhs, std::move(rebraided.top), {});
    const InstancedAccel b(scene, bvhs, std::move(plain), {});
    EXPECT_NEAR(*a.stats().sah, *b.stats().sah, 0.02 * *b.stats().sah);
}

TEST(RebraidBuilder, SingleLeafObjectsAndEmptyMeshes) {
    Scene scene;
    Mesh single;
    single.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    single.triangles = {{0, 1, 2}};
    scene.meshes.push_back(single);
    scene.meshes.push_back(Mesh{});  // empty: its instances are left out
    for (int i = 0; i < 50; ++i)
        scene.instances.push_back(
            {MeshId(i % 2), AffineTransform::translate({0.01f * float(i), 0.0f, 0.0f})});
    const std::vector<ObjectBvh> bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    const RebraidBuild build = build_rebraid(scene, bvhs, {.open_threshold = 0.0f});
    EXPECT_EQ(build.opened, 0u);  // leaves cannot be opened
    EXPECT_EQ(build.brefs, 25u);
    const InstancedAccel accel(scene, bvhs, RebraidBuild(build).top, {});
    test::expect_each_reached_once(test::reach_counts(scene, accel));
    const Hit hit = accel.intersect({{0.2f, 0.2f, 1.0f}, 0.0f, {0, 0, -1}});
    EXPECT_TRUE(hit.is_hit());
    EXPECT_FLOAT_EQ(hit.t, 1.0f);
}

TEST(RebraidBuilder, InstanceSubsetReachesExactlyItsInstances) {
    const Scene scene = test::make_overlap_scene(200, 3);
    const std::vector<ObjectBvh> bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    std::vector<InstanceId> odd;
    for (InstanceId i = 1; i < scene.instances.size(); i += 2) odd.push_back(i);
    // The budget of the subset's own count (no search for a larger one).
    RebraidBuild build = build_rebraid(scene, bvhs, {.budget_doublings = 0}, odd);
    EXPECT_EQ(build.budget, 4u * odd.size());
    EXPECT_GT(build.opened, 0u);
    const InstancedAccel accel(scene, bvhs, std::move(build.top), {});
    const test::ReachCounts counts = test::reach_counts(scene, accel);
    for (std::size_t i = 0; i < counts.reached.size(); ++i)
        for (std::size_t p = 0; p < counts.reached[i].size(); ++p)
            ASSERT_EQ(counts.reached[i][p], i % 2 == 1 ? counts.held[i][p] : 0) << "instance " << i;
    // A subset of every instance in scene order is the ordinary build.
    std::vector<InstanceId> all(scene.instances.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = InstanceId(i);
    const InstancedAccel from_subset(scene, bvhs, build_rebraid(scene, bvhs, {}, all).top, {});
    const InstancedAccel ordinary(scene, bvhs, build_rebraid(scene, bvhs, {}).top, {});
    EXPECT_EQ(from_subset.stats().structure_hash, ordinary.stats().structure_hash);
    const InstanceId past_end[] = {InstanceId(scene.instances.size())};
    EXPECT_THROW(build_rebraid(scene, bvhs, {}, past_end), Error);
}

TEST(RebraidBuilder, EmptySceneHasNoItems) {
    const Scene scene;
    const RebraidBuild build = build_rebraid(scene, {}, {});
    EXPECT_TRUE(build.top.root.is_empty());
    EXPECT_EQ(build.brefs, 0u);
    const InstancedAccel accel(scene, {}, RebraidBuild(build).top, {});
    EXPECT_FALSE(accel.intersect({{0, 0, 0}, 0.0f, {1, 0, 0}}).is_hit());
}

TEST(RebraidBuilder, SameStructureOnOneTwoAndEightThreads) {
    std::vector<test::NamedScene> scenes = rebraid_scenes();
    for (const std::string& file : test::shared_scene_files())
        scenes.push_back({file, load_gltf_scene(std::string(REBRAID_SHARED_SCENES) + "/" + file)});
    // A small threshold makes the parallel opening, binning and partitioning paths run;
    // meshes of two instances or more take their BRefs' boxes from support tables, the
    // others from searches of their BVHs.
    RebraidSettings settings;
    settings.build.parallel_threshold = 64;
    settings.support_table_instances = 2;
    for (const test::NamedScene& named : scenes) {
        SCOPED_TRACE(named.name);
        // The object BVHs are built on each thread count too: the whole build is checked.
        test::expect_same_hash_on_threads({1, 2, 8}, [&] {
            const InstancedAccel accel = build_rebraid_accel(
                named.scene, own_object_bvh_builder({.parallel_threshold = 256}), settings);
            return *accel.stats().structure_hash;
        });
    }
}

TEST(RebraidBuilder, SameStructureForAnyTaskGranularity) {
    // Tasks are numbered into the tree by one layout pass, so how finely the build is cut
    // into tasks must not change a bit of it (nor must one thread, which spawns none).
    tbb::global_control allow_two(tbb::global_control::max_allowed_parallelism, 2);
    const Scene scene = test::make_overlap_scene(300, 5);
    const std::vector<ObjectBvh> bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    auto hash_with = [&](std::size_t task_threshold, std::size_t parallel_threshold, int threads) {
        RebraidSettings settings;
        settings.build.task_threshold = task_threshold;
        settings.build.parallel_threshold = parallel_threshold;
        return test::hash_on_threads(threads, [&] {
            const InstancedAccel accel(scene, bvhs, build_rebraid(scene, bvhs, settings).top, {});
            return *accel.stats().structure_hash;
        });
    };
    // A low parallel threshold puts large children last in the numbering (as
    // grow_wide_subtree does), which the layout pass must reproduce.
    for (const std::size_t parallel_threshold : {std::size_t(64), std::size_t(8192)}) {
        SCOPED_TRACE(parallel_threshold);
        const std::uint64_t serial = hash_with(1u << 30, parallel_threshold, 1);
        EXPECT_EQ(serial, hash_with(1, parallel_threshold, 2));
        EXPECT_EQ(serial, hash_with(16, parallel_threshold, 2));
        EXPECT_EQ(serial, hash_with(200, parallel_threshold, 2));
    }
}

TEST(RebraidSettings, RejectsOutOfRangeValues) {
    EXPECT_THROW((RebraidSettings{.open_threshold = -0.1f}.validate()), Error);
    EXPECT_THROW((RebraidSettings{.budget_factor = -1.0f}.validate()), Error);
    EXPECT_THROW((RebraidSettings{.primitives_per_bref = 0.0f}.validate()), Error);
    EXPECT_NO_THROW(RebraidSettings{}.validate());
}

}  // namespace
}  // namespace rebraid
