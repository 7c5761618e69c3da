// Updating the BVH of a deforming mesh: every strategy keeps a valid tree (each triangle in
// one leaf, boxes containing their children, the same hits as Embree flat on the same frame,
// the same structure on any thread count); rotations never do worse than refit;
// restructuring repairs a degraded tree; auto refits, repairs and rebuilds by its factors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/dynamic/object_bvh_update.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/top_level/bvh_stats.h"
#include "support/object_bvh_checks.h"
#include "support/reachability.h"
#include "support/thread_count_hash.h"
#include "support/update_test_scenes.h"

namespace rebraid {
namespace {

using test::check_subtree;
using test::deformed;
using test::expect_hits_of_embree_flat;
using test::expect_valid;
using test::rest_mesh;
using test::shuffled;
using test::structure_hash;
using test::unwelded;
using test::update_through_frames;

ObjectBvhUpdateSettings with_strategy(UpdateStrategy strategy) {
    ObjectBvhUpdateSettings settings;
    settings.strategy = strategy;
    return settings;
}

struct StrategyCase {
    std::string name;
    ObjectBvhUpdateSettings settings;
};

/// How GoogleTest shows a case (in ctest's listing too): its name, not its bytes.
void PrintTo(const StrategyCase& strategy_case, std::ostream* out) {
    *out << strategy_case.name;
}

std::vector<StrategyCase> strategy_cases() {
    std::vector<StrategyCase> cases;
    for (UpdateStrategy strategy : kUpdateStrategies) {
        ObjectBvhUpdateSettings settings;
        settings.strategy = strategy;
        // Small subtrees qualify, so restructuring acts on this small mesh.
        settings.restructure.min_subtree_prims = 16;
        std::string name(update_strategy_name(strategy));
        cases.push_back({name, settings});
        if (strategy == UpdateStrategy::restructure) {
            settings.restructure_rotates = true;  // pre-split, scattered leaf positions
            cases.push_back({"restructure_rotates", settings});
            settings.restructure_rotates = false;
        }
        if (strategy == UpdateStrategy::rotate) {
            // The default is split_merge, lazy, two moves per node; Kopta's schedule (pre-split,
            // one move, every node) and a lazy pre-split pass with three moves besides it.
            settings.rotation.leaf_mode = RotationLeafMode::pre_split;
            settings.rotation.min_growth_to_search = 0.0f;
            settings.rotation.max_rotations_per_node = 1;
            cases.push_back({"rotate_pre_split_eager", settings});
            settings.rotation.min_growth_to_search = 0.01f;
            settings.rotation.max_rotations_per_node = 3;
            cases.push_back({"rotate_pre_split_lazy_three_per_node", settings});
            settings.rotation = {};
        }
        if (strategy == UpdateStrategy::automatic) {
            // Every repair, each from the first frame on (the test's explosion passes 1.0
            // at once), with a rebuild factor the explosion passes within the frames.
            settings.repair_sah_factor = 1.0;
            for (UpdateStrategy repair :
                 {UpdateStrategy::rotate, UpdateStrategy::restructure, UpdateStrategy::treelet}) {
                settings.auto_repair = repair;
                cases.push_back(
                    {"auto_repair_" + std::string(update_strategy_name(repair)), settings});
            }
        }
    }
    return cases;
}

/// Builds on the rest pose, then updates through `frames` deformed frames; returns the BVH.
ObjectBvh animate(const Mesh& rest, const ObjectBvhUpdateSettings& settings, int frames,
                  std::vector<ObjectBvhUpdateReport>* reports = nullptr) {
    ObjectBvhUpdater updater(settings);
    return update_through_frames(rest, frames, build_object_bvh(rest),
                                 [&](const Mesh& mesh, ObjectBvh& bvh, int) {
                                     const ObjectBvhUpdateReport report = updater.update(mesh, bvh);
                                     if (reports) reports->push_back(report);
                                 });
}

class EveryStrategy : public testing::TestWithParam<StrategyCase> {};

TEST_P(EveryStrategy, KeepsAValidTreeEveryFrame) {
    const Mesh rest = rest_mesh();
    ObjectBvhUpdater updater(GetParam().settings);
    update_through_frames(rest, 6, build_object_bvh(rest),
                          [&](const Mesh& mesh, ObjectBvh& bvh, int frame) {
                              SCOPED_TRACE("frame " + std::to_string(frame));
                              const ObjectBvhUpdateReport report = updater.update(mesh, bvh);
                              expect_valid(mesh, bvh);
                              EXPECT_NEAR(report.sah, object_bvh_sah(bvh), 1e-5 * report.sah);
                              EXPECT_NE(report.applied, UpdateStrategy::automatic);
                              EXPECT_GE(report.update_ms, 0.0);
                          });
}

TEST_P(EveryStrategy, HitsEqualAFreshBuildAfterDeforming) {
    const Mesh rest = rest_mesh();
    const ObjectBvh bvh = animate(rest, GetParam().settings, 5);
    expect_hits_of_embree_flat(deformed(rest, 1.0f), bvh);
}

TEST_P(EveryStrategy, SameStructureOnOneTwoAndEightThreads) {
    const Mesh rest = rest_mesh();
    test::expect_same_hash_on_threads(
        {1, 2, 8}, [&] { return structure_hash(animate(rest, GetParam().settings, 4)); });
}

INSTANTIATE_TEST_SUITE_P(ObjectBvhUpdate, EveryStrategy, testing::ValuesIn(strategy_cases()),
                         [](const testing::TestParamInfo<StrategyCase>& info) {
                             return info.param.name;
                         });

TEST(BvhRotator, NeverRaisesSahOverRefitOfTheSameFrame) {
    const Mesh rest = rest_mesh();
    for (RotationLeafMode mode : {RotationLeafMode::pre_split, RotationLeafMode::split_merge}) {
        RotationSettings settings;
        settings.leaf_mode = mode;
        const ObjectBvh built = build_object_bvh(
            rest, {.max_leaf_size = mode == RotationLeafMode::pre_split ? 1u : 4u});
        BvhRotator rotator;
        double total_gain = 0.0;
        update_through_frames(rest, 5, built, [&](const Mesh& mesh, ObjectBvh& bvh, int frame) {
            ObjectBvh refit_only = bvh;
            const double refit_sah = refit_object_bvh(mesh, refit_only);
            const RotationPassStats stats = rotator.refit_and_rotate(mesh, bvh, settings);
            const double rotated_sah = object_bvh_sah(bvh);
            EXPECT_LE(rotated_sah, refit_sah * (1.0 + 1e-6)) << "frame " << frame;
            EXPECT_NEAR(stats.sah, rotated_sah, 1e-5 * rotated_sah);
            total_gain += refit_sah - rotated_sah;
            EXPECT_GT(stats.swaps + stats.exchanges + stats.pull_ups + stats.splits + stats.merges,
                      0u);
        });
        EXPECT_GT(total_gain, 0.0);
    }
}

TEST(BvhRotator, RotationsFromTheRestPoseKeepTheTree) {
    // With nothing moved, a pass only refits and applies strictly improving moves: the
    // triangles and the root box stay the same.
    const Mesh rest = rest_mesh();
    for (RotationLeafMode mode : {RotationLeafMode::pre_split, RotationLeafMode::split_merge}) {
        ObjectBvh bvh = build_object_bvh(
            rest, {.max_leaf_size = mode == RotationLeafMode::pre_split ? 1u : 4u});
        const double built_sah = object_bvh_sah(bvh);
        BvhRotator rotator;
        RotationSettings settings;
        settings.leaf_mode = mode;
        const RotationPassStats stats = rotator.refit_and_rotate(rest, bvh, settings);
        EXPECT_LE(stats.sah, built_sah * (1.0 + 1e-6));
        expect_valid(rest, bvh);
    }
}

TEST(BvhRotator, RespectsTheDepthLimit) {
    const Mesh rest = unwelded(rest_mesh());
    ObjectBvh bvh = build_object_bvh(rest, {.max_leaf_size = 1});
    RotationSettings settings;
    settings.leaf_mode = RotationLeafMode::pre_split;
    settings.min_growth_to_search = 0.0f;  // every node, every pass
    settings.max_depth = 6;
    settings.max_rotations_per_node = 4;
    BvhRotator rotator;
    for (int frame = 1; frame <= 4; ++frame) {
        const Mesh mesh = shuffled(rest, float(frame) / 4.0f);
        rotator.refit_and_rotate(mesh, bvh, settings);
        expect_valid(mesh, bvh);
    }
    // The builder's tree of 3840 triangles is 4-5 levels deep; rotations may deepen it to
    // the limit but not past it.
    std::vector<int> reached(rest.triangles.size(), 0);
    std::size_t errors = 0;
    EXPECT_LE(check_subtree(bvh, bvh.root, bvh.bounds, reached, errors), 6);
}

TEST(SelectiveRestructurer, LowersTheSahOfABadlyDegradedTree) {
    test::DegradedTree degraded = test::make_degraded_tree();
    const Mesh& mesh = degraded.mesh;
    ObjectBvh& bvh = degraded.bvh;
    const double refit_sah = degraded.refit_sah;
    ASSERT_GT(refit_sah, 2.0 * degraded.rebuilt_sah) << "the shuffle should degrade the refit tree";
    SelectiveRestructurer restructurer;
    RestructureSettings settings;
    settings.min_subtree_prims = 16;
    settings.max_rebuilt_fraction = 0.5;
    const RestructureStats stats = restructurer.restructure(mesh, bvh, settings);
    expect_valid(mesh, bvh);
    const double restructured_sah = object_bvh_sah(bvh);
    EXPECT_NEAR(stats.sah, restructured_sah, 1e-5 * restructured_sah);
    EXPECT_GT(stats.subtrees_rebuilt, 0u);
    EXPECT_LE(stats.prims_rebuilt, mesh.triangles.size() / 2);
    EXPECT_LT(restructured_sah, 0.9 * refit_sah);
    expect_hits_of_embree_flat(mesh, bvh);
}

TEST(SelectiveRestructurer, NeverRaisesTheSah) {
    const Mesh rest = rest_mesh();
    SelectiveRestructurer restructurer;
    RestructureSettings settings;
    settings.min_subtree_prims = 16;
    update_through_frames(
        rest, 4, build_object_bvh(rest), [&](const Mesh& mesh, ObjectBvh& bvh, int frame) {
            const double refit_sah = refit_object_bvh(mesh, bvh);
            restructurer.restructure(mesh, bvh, settings);
            EXPECT_LE(object_bvh_sah(bvh), refit_sah * (1.0 + 1e-6)) << "frame " << frame;
        });
}

TEST(SelectiveRestructurer, RebuildsScatteredPreSplitSubtreesAfterRotations) {
    // Rotations move single-triangle leaves between subtrees, so a subtree's triangles no
    // longer occupy one leaf-order range; the rebuild must reuse exactly their positions.
    const Mesh rest = unwelded(rest_mesh());
    ObjectBvh bvh = build_object_bvh(rest, {.max_leaf_size = 1});
    BvhRotator rotator;
    const RotationSettings pre_split{.leaf_mode = RotationLeafMode::pre_split};
    for (int frame = 1; frame <= 3; ++frame)
        rotator.refit_and_rotate(shuffled(rest, 0.1f * frame), bvh, pre_split);
    const Mesh mesh = shuffled(rest, 0.5f);
    const double rotated_sah = rotator.refit_and_rotate(mesh, bvh, pre_split).sah;
    SelectiveRestructurer restructurer;
    RestructureSettings settings;
    settings.min_subtree_prims = 16;
    settings.max_rebuilt_fraction = 0.5;
    const RestructureStats stats = restructurer.restructure(mesh, bvh, settings);
    EXPECT_GT(stats.scattered_subtrees_rebuilt, 0u);
    EXPECT_LT(stats.sah, rotated_sah);
    expect_valid(mesh, bvh);
    test::for_each_leaf(bvh.nodes, bvh.root,
                        [&](NodeRef leaf) { EXPECT_EQ(leaf.prim_count(), 1u); });
    expect_hits_of_embree_flat(mesh, bvh);
}

TEST(ObjectBvhUpdater, AutoRebuildsOncePastTheFactor) {
    const Mesh rest = unwelded(rest_mesh());
    ObjectBvhUpdateSettings settings;
    settings.strategy = UpdateStrategy::automatic;
    settings.rebuild_sah_factor = 1.3;
    ObjectBvh bvh = build_object_bvh(rest);
    ObjectBvhUpdater updater(settings);
    // Nothing moved: a refit is enough, and the tree given first is the reference.
    ObjectBvhUpdateReport report = updater.update(rest, bvh);
    EXPECT_EQ(report.applied, UpdateStrategy::refit);
    EXPECT_NEAR(report.sah_over_rebuild, 1.0, 1e-6);
    // A shuffle passes any reasonable factor: rebuilt, and the new tree is the reference.
    const Mesh mesh = shuffled(rest, 1.0f);
    ObjectBvh refit_copy = bvh;
    ASSERT_GT(refit_object_bvh(mesh, refit_copy), 1.3 * object_bvh_sah(bvh));
    report = updater.update(mesh, bvh);
    EXPECT_EQ(report.applied, UpdateStrategy::rebuild);
    EXPECT_DOUBLE_EQ(report.sah_over_rebuild, 1.0);
    expect_valid(mesh, bvh);
}

TEST(ObjectBvhUpdater, AutoStaysWithinTheFactorWithoutRebuilding) {
    const Mesh rest = rest_mesh();
    for (double factor : {1.05, 1e9}) {
        ObjectBvhUpdateSettings settings;
        settings.strategy = UpdateStrategy::automatic;
        settings.auto_repair = UpdateStrategy::refit;  // no repair: the SAH grows
        settings.rebuild_sah_factor = factor;
        std::vector<ObjectBvhUpdateReport> reports;
        animate(rest, settings, 8, &reports);
        int rebuilds = 0;
        for (const ObjectBvhUpdateReport& report : reports) {
            rebuilds += report.applied == UpdateStrategy::rebuild;
            if (report.applied != UpdateStrategy::rebuild) {
                EXPECT_LE(report.sah_over_rebuild, factor);
            }
        }
        if (factor > 1e8) {
            EXPECT_EQ(rebuilds, 0);
        } else {
            EXPECT_GT(rebuilds, 0);
        }
    }
}

TEST(ObjectBvhUpdater, AutoRepairsOnlyBetweenItsTwoFactors) {
    const Mesh rest = rest_mesh();
    for (UpdateStrategy repair :
         {UpdateStrategy::treelet, UpdateStrategy::restructure, UpdateStrategy::rotate}) {
        SCOPED_TRACE(std::string(update_strategy_name(repair)));
        ObjectBvhUpdateSettings settings;
        settings.strategy = UpdateStrategy::automatic;
        settings.auto_repair = repair;
        settings.repair_sah_factor = 1.02;
        settings.rebuild_sah_factor = 1e9;
        settings.restructure.min_subtree_prims = 16;
        // Pre-split rotations also check the first update's rebuild to one triangle per leaf.
        settings.rotation.leaf_mode = RotationLeafMode::pre_split;
        std::vector<ObjectBvhUpdateReport> reports;
        animate(rest, settings, 12, &reports);
        int repairs = 0;
        double previous_ratio = 0.0;
        for (std::size_t frame = 0; frame < reports.size(); ++frame) {
            const ObjectBvhUpdateReport& report = reports[frame];
            if (frame == 0 && repair == UpdateStrategy::rotate) {
                // Rotations need one triangle per leaf: the first update rebuilds so.
                EXPECT_EQ(report.applied, UpdateStrategy::rebuild);
                previous_ratio = report.sah_over_rebuild;
                continue;
            }
            EXPECT_NE(report.applied, UpdateStrategy::rebuild);
            // Rotations are chosen by the previous frame's SAH (they replace the refit),
            // the others by this frame's refit.
            const double decided_by =
                repair == UpdateStrategy::rotate ? previous_ratio : report.sah_over_rebuild;
            if (report.applied == repair) {
                ++repairs;
                if (repair == UpdateStrategy::rotate) {
                    EXPECT_GT(decided_by, 1.02);
                }
            } else {
                EXPECT_EQ(report.applied, UpdateStrategy::refit);
                EXPECT_LE(decided_by, 1.02);
            }
            previous_ratio = report.sah_over_rebuild;
        }
        EXPECT_GT(repairs, 0);
    }
}

TEST(ObjectBvhUpdater, AutoBelowTheRepairFactorIsExactlyARefit) {
    // Smooth motion within repair_sah_factor: auto must do what refit does, nothing more.
    const Mesh rest = rest_mesh();
    ObjectBvhUpdateSettings automatic = with_strategy(UpdateStrategy::automatic);
    automatic.repair_sah_factor = 1e9 - 1;
    automatic.rebuild_sah_factor = 1e9;
    const ObjectBvh refit = animate(rest, with_strategy(UpdateStrategy::refit), 5);
    EXPECT_EQ(structure_hash(animate(rest, automatic, 5)), structure_hash(refit));
}

TEST(ObjectBvhUpdater, RotatePreSplitRebuildsWithOneTrianglePerLeaf) {
    const Mesh rest = rest_mesh();
    ObjectBvh bvh = build_object_bvh(rest);
    ObjectBvhUpdateSettings settings = with_strategy(UpdateStrategy::rotate);
    settings.rotation.leaf_mode = RotationLeafMode::pre_split;
    ObjectBvhUpdater updater(settings);
    EXPECT_EQ(updater.rebuild_settings().max_leaf_size, 1u);
    EXPECT_EQ(updater.update(rest, bvh).applied, UpdateStrategy::rebuild);
    EXPECT_EQ(updater.update(deformed(rest, 0.5f), bvh).applied, UpdateStrategy::rotate);
    std::vector<int> leaves_over_one;
    test::for_each_leaf(bvh.nodes, bvh.root, [&](NodeRef leaf) {
        if (leaf.prim_count() > 1) leaves_over_one.push_back(int(leaf.prim_count()));
    });
    EXPECT_TRUE(leaves_over_one.empty());
}

TEST(UpdateStrategy, NamesRoundTrip) {
    for (UpdateStrategy strategy : kUpdateStrategies)
        EXPECT_EQ(parse_update_strategy(update_strategy_name(strategy)), strategy);
    EXPECT_EQ(update_strategy_name(UpdateStrategy::automatic), "auto");
    EXPECT_THROW(parse_update_strategy("rotations"), Error);
}

TEST(ObjectBvhUpdater, RejectsBadSettingsAndAnotherMesh) {
    ObjectBvhUpdateSettings settings;
    settings.rebuild_sah_factor = 0.5;
    EXPECT_THROW(ObjectBvhUpdater{settings}, Error);
    settings = {};
    settings.rotation.max_leaf_size = 17;
    EXPECT_THROW(ObjectBvhUpdater{settings}, Error);
    settings = {};
    settings.restructure.max_rebuilt_fraction = 2.0;
    EXPECT_THROW(ObjectBvhUpdater{settings}, Error);
    settings = {};
    settings.repair_sah_factor = 0.9;
    EXPECT_THROW(ObjectBvhUpdater{settings}, Error);
    settings = {};
    settings.auto_repair = UpdateStrategy::rebuild;
    EXPECT_THROW(ObjectBvhUpdater{settings}, Error);
    settings = {};
    settings.treelet.max_treelet_leaves = 1;
    EXPECT_THROW(ObjectBvhUpdater{settings}, Error);
    const Mesh rest = rest_mesh();
    ObjectBvh bvh = build_object_bvh(rest);
    ObjectBvhUpdater updater(with_strategy(UpdateStrategy::refit));
    EXPECT_THROW(updater.update(make_box(), bvh), Error);
    EXPECT_THROW(refit_object_bvh(make_box(), bvh), Error);
}

TEST(RefitObjectBvh, MatchesTheBoxesOfTheDeformedMesh) {
    const Mesh rest = rest_mesh();
    ObjectBvh bvh = build_object_bvh(rest);
    const ObjectBvh built = bvh;
    const Mesh mesh = deformed(rest, 0.7f);
    const double sah = refit_object_bvh(mesh, bvh);
    expect_valid(mesh, bvh);
    EXPECT_NEAR(sah, object_bvh_sah(bvh), 1e-5 * sah);
    // Same tree: the same references everywhere, only boxes and triangle copies changed.
    ASSERT_EQ(bvh.nodes.size(), built.nodes.size());
    for (std::size_t i = 0; i < bvh.nodes.size(); ++i)
        for (int slot = 0; slot < kBvhWidth; ++slot)
            EXPECT_EQ(bvh.nodes[i].children[slot], built.nodes[i].children[slot]);
    EXPECT_EQ(bvh.prim_ids, built.prim_ids);
    // Refitting back to the rest pose restores the built boxes exactly.
    refit_object_bvh(rest, bvh);
    EXPECT_EQ(structure_hash(bvh), structure_hash(built));
}

}  // namespace
}  // namespace rebraid
