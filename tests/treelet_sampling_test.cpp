// Treelet sampling (TreeletSampler): after refits of a deforming mesh it never raises the SAH,
// repairs a degraded tree, keeps every triangle in one leaf under boxes that contain it,
// answers rays as Embree flat does, and gives the same tree on any thread count.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cstdint>
#include <string>
#include <vector>

#include "object_bvh_checks.h"
#include "rebraid/bvh_stats.h"
#include "rebraid/error.h"
#include "rebraid/object_bvh_refit.h"
#include "rebraid/treelet_sampling.h"

namespace rebraid {
namespace {

using test::deformed;
using test::expect_hits_of_embree_flat;
using test::expect_valid;
using test::rest_mesh;
using test::shuffled;
using test::structure_hash;
using test::unwelded;

/// Refits and samples treelets through `frames` frames of `deformed`; returns the tree.
ObjectBvh sample_through_frames(const Mesh& rest, int frames, const TreeletSettings& settings,
                                BuildSettings build = {}) {
    ObjectBvh bvh = build_object_bvh(rest, build);
    TreeletSampler sampler;
    sampler.reset(bvh);
    for (int frame = 1; frame <= frames; ++frame) {
        const Mesh mesh = deformed(rest, float(frame) / float(frames));
        refit_object_bvh(mesh, bvh);
        sampler.optimize(mesh, bvh, settings);
    }
    return bvh;
}

TEST(TreeletSampler, NeverRaisesTheSahOverRefitAlone) {
    const Mesh rest = rest_mesh();
    for (std::uint32_t leaf_size : {1u, 4u}) {
        SCOPED_TRACE("max_leaf_size " + std::to_string(leaf_size));
        ObjectBvh bvh = build_object_bvh(rest, {.max_leaf_size = leaf_size});
        TreeletSampler sampler;
        sampler.reset(bvh);
        double total_gain = 0.0;
        for (int frame = 1; frame <= 6; ++frame) {
            const Mesh mesh = deformed(rest, float(frame) / 6.0f);
            const double refit_sah = refit_object_bvh(mesh, bvh);
            const TreeletStats stats = sampler.optimize(mesh, bvh);
            const double sah = object_bvh_sah(bvh);
            EXPECT_LE(sah, refit_sah * (1.0 + 1e-6)) << "frame " << frame;
            EXPECT_NEAR(stats.sah, sah, 1e-5 * sah) << "frame " << frame;
            EXPECT_LE(stats.applied, stats.improved);
            EXPECT_LE(stats.improved, stats.sampled);
            total_gain += refit_sah - sah;
            expect_valid(mesh, bvh);
        }
        EXPECT_GT(total_gain, 0.0);
    }
}

TEST(TreeletSampler, RepairsABadlyDegradedTree) {
    const Mesh rest = unwelded(rest_mesh());
    const Mesh mesh = shuffled(rest, 0.5f);
    // One triangle per leaf: treelets move whole subtrees, so they can regroup triangles
    // only when leaves do not tie them together.
    ObjectBvh bvh = build_object_bvh(rest, {.max_leaf_size = 1});
    TreeletSampler sampler;
    sampler.reset(bvh);
    const double refit_sah = refit_object_bvh(mesh, bvh);
    ASSERT_GT(refit_sah, 2.0 * object_bvh_sah(build_object_bvh(mesh)))
        << "the shuffle should degrade the refit tree";
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
    std::vector<std::uint64_t> hashes;
    const tbb::global_control allow_two(tbb::global_control::max_allowed_parallelism, 2);
    for (int threads : {1, 2}) {
        tbb::task_arena arena(threads);
        arena.execute(
            [&] { hashes.push_back(structure_hash(sample_through_frames(rest, 4, settings))); });
    }
    EXPECT_EQ(hashes[0], hashes[1]);
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
