// Treelet sampling (TreeletSampler): after refits of a deforming mesh it never raises the SAH,
// repairs a degraded tree, keeps every triangle in one leaf under boxes that contain it,
// answers rays as Embree flat does, and gives the same tree on any thread count.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/dynamic/object_bvh_refit.h"
#include "rebraid/dynamic/treelet_sampling.h"
#include "rebraid/top_level/bvh_stats.h"
#include "support/object_bvh_checks.h"
#include "support/thread_count_hash.h"
#include "support/update_test_scenes.h"

namespace rebraid {
namespace {

using test::deformed;
using test::expect_hits_of_embree_flat;
using test::expect_valid;
using test::rest_mesh;
using test::shuffled;
using test::structure_hash;
using test::unwelded;
using test::update_through_frames;

/// Refits and samples treelets through `frames` frames of `deformed`; returns the tree.
ObjectBvh sample_through_frames(const Mesh& rest, int frames, const TreeletSettings& settings,
                                BuildSettings build = {}) {
    ObjectBvh bvh = build_object_bvh(rest, build);
    TreeletSampler sampler;
    sampler.reset(bvh);
    return update_through_frames(rest, frames, std::move(bvh),
                                 [&](const Mesh& mesh, ObjectBvh& tree, int) {
                                     refit_object_bvh(mesh, tree);
                                     sampler.optimize(mesh, tree, settings);
                                 });
}

TEST(TreeletSampler, NeverRaisesTheSahOverRefitAlone) {
    const Mesh rest = rest_mesh();
    for (std::uint32_t leaf_size : {1u, 4u}) {
        SCOPED_TRACE("max_leaf_size " + std::to_string(leaf_size));
        ObjectBvh bvh = build_object_bvh(rest, {.max_leaf_size = leaf_size});
        TreeletSampler sampler;
        sampler.reset(bvh);
        double total_gain = 0.0;
        update_through_frames(rest, 6, std::move(bvh),
                              [&](const Mesh& mesh, ObjectBvh& tree, int frame) {
                                  const double refit_sah = refit_object_bvh(mesh, tree);
                                  const TreeletStats stats = sampler.optimize(mesh, tree);
                                  const double sah = object_bvh_sah(tree);
                                  EXPECT_LE(sah, refit_sah * (1.0 + 1e-6)) << "frame " << frame;
                                  EXPECT_NEAR(stats.sah, sah, 1e-5 * sah) << "frame " << frame;
                                  EXPECT_LE(stats.applied, stats.improved);
                                  EXPECT_LE(stats.improved, stats.sampled);
                                  total_gain += refit_sah - sah;
                                  expect_valid(mesh, tree);
                              });
        EXPECT_GT(total_gain, 0.0);
    }
}

TEST(TreeletSampler, RepairsABadlyDegradedTree) {
    // One triangle per leaf: treelets move whole subtrees, so they can regroup triangles
    // only when leaves do not tie them together.
    test::DegradedTree degraded = test::make_degraded_tree({.max_leaf_size = 1});
    const Mesh& mesh = degraded.mesh;
    ObjectBvh& bvh = degraded.bvh;
    const double refit_sah = degraded.refit_sah;
    ASSERT_GT(refit_sah, 2.0 * degraded.rebuilt_sah) << "the shuffle should degrade the refit tree";
    // The sampler knows the tree as built, so it sees how much the refit grew each box.
    TreeletSampler sampler;
    sampler.reset(degraded.built);
    TreeletSettings settings;
    settings.root_fraction = 0.5;
    // Restructurings applied over the passes (a build that rounds differently may finish the
    // repair before the last pass, which then applies nothing).
    std::uint64_t applied = 0;
    for (int pass = 0; pass < 4; ++pass) applied += sampler.optimize(mesh, bvh, settings).applied;
    EXPECT_GT(applied, 0u);
    EXPECT_LT(object_bvh_sah(bvh), 0.9 * refit_sah);
    expect_valid(mesh, bvh);
    expect_hits_of_embree_flat(mesh, bvh);
}

TEST(TreeletSampler, HitsEqualEmbreeFlatAfterDeforming) {
    const Mesh rest = rest_mesh();
    for (std::uint32_t leaf_size : {1u, 4u}) {
        SCOPED_TRACE("max_leaf_size " + std::to_string(leaf_size));
        const ObjectBvh bvh = sample_through_frames(rest, 5, {}, {.max_leaf_size = leaf_size});
        const Mesh mesh = deformed(rest, 1.0f);
        expect_valid(mesh, bvh);
        expect_hits_of_embree_flat(mesh, bvh);
    }
}

TEST(TreeletSampler, SameStructureOnOneAndTwoThreads) {
    const Mesh rest = rest_mesh();
    TreeletSettings settings;
    settings.root_fraction = 0.3;
    test::expect_same_hash_on_threads(
        {1, 2}, [&] { return structure_hash(sample_through_frames(rest, 4, settings)); });
}

TEST(TreeletSampler, TheSeedChangesWhichTreeletsAreDrawn) {
    const Mesh rest = rest_mesh();
    TreeletSettings first, second;
    second.seed = first.seed + 1000;
    EXPECT_NE(structure_hash(sample_through_frames(rest, 3, first)),
              structure_hash(sample_through_frames(rest, 3, second)));
}

TEST(TreeletSampler, NeverDeepensTheTree) {
    const Mesh rest = unwelded(rest_mesh());
    ObjectBvh bvh = build_object_bvh(rest, {.max_leaf_size = 1});
    const auto depth_of = [](const ObjectBvh& tree) {
        std::vector<int> reached(tree.prim_ids.size(), 0);
        std::size_t errors = 0;
        return test::check_subtree(tree, tree.root, tree.bounds, reached, errors);
    };
    const int built_depth = depth_of(bvh);
    TreeletSampler sampler;
    sampler.reset(bvh);
    TreeletSettings settings;
    settings.root_fraction = 1.0;
    for (int frame = 1; frame <= 4; ++frame) {
        const Mesh mesh = shuffled(rest, 0.25f * float(frame));
        refit_object_bvh(mesh, bvh);
        sampler.optimize(mesh, bvh, settings);
        EXPECT_LE(depth_of(bvh), built_depth) << "frame " << frame;
    }
}

TEST(TreeletSampler, RejectsBadSettingsAndAnotherMesh) {
    const Mesh rest = rest_mesh();
    ObjectBvh bvh = build_object_bvh(rest);
    TreeletSampler sampler;
    const auto rejects = [&](const TreeletSettings& settings) {
        EXPECT_THROW(sampler.optimize(rest, bvh, settings), Error);
    };
    rejects({.root_fraction = 0.0});
    rejects({.root_fraction = 1.5});
    rejects({.max_treelet_leaves = 1});
    rejects({.max_treelet_leaves = 65});
    rejects({.descendant_weight = -1.0});
    EXPECT_THROW(sampler.optimize(make_box(), bvh), Error);
}

}  // namespace
}  // namespace rebraid
