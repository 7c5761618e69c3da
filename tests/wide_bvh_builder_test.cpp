#include "rebraid/wide_bvh_builder.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <vector>

#include "rebraid/error.h"
#include "rebraid/object_bvh.h"
#include "rebraid/structure_hash.h"
#include "test_scenes.h"

namespace rebraid {
namespace {

/// Walks the tree checking that each child box holds everything below it; returns, per
/// prim slot, how many leaves reference it.
void check_subtree(const WideBvh& bvh, std::span<const BuildPrim> prims, NodeRef ref,
                   const BBox3f& box, std::uint32_t max_leaf, int depth,
                   std::vector<int>& references) {
    ASSERT_LE(depth, kMaxBvhDepth);
    if (ref.is_leaf()) {
        ASSERT_LE(ref.prim_count(), max_leaf);
        for (std::uint32_t i = ref.first_prim(); i < ref.first_prim() + ref.prim_count(); ++i) {
            ASSERT_LT(i, prims.size());
            ++references[i];
            EXPECT_TRUE(box.contains(prims[i].bounds));
        }
        return;
    }
    ASSERT_TRUE(ref.is_inner());
    ASSERT_LT(ref.node_id(), bvh.nodes.size());
    const WideNode& node = bvh.nodes[ref.node_id()];
    const int count = node.child_count();
    EXPECT_GE(count, 2);
    for (int i = count; i < kBvhWidth; ++i) EXPECT_TRUE(node.children[i].is_empty());
    for (int i = 0; i < count; ++i) {
        EXPECT_TRUE(box.contains(node.child_bounds(i)));
        check_subtree(bvh, prims, node.children[i], node.child_bounds(i), max_leaf, depth + 1,
                      references);
    }
}

void expect_valid_tree(const WideBvh& bvh, std::span<const BuildPrim> prims,
                       std::uint32_t max_leaf) {
    std::vector<int> references(prims.size(), 0);
    check_subtree(bvh, prims, bvh.root, bvh.bounds, max_leaf, 0, references);
    for (std::size_t i = 0; i < prims.size(); ++i)
        ASSERT_EQ(references[i], 1) << "prim slot " << i << " is not referenced exactly once";
}

std::uint64_t tree_hash(const WideBvh& bvh, std::span<const BuildPrim> prims) {
    StructureHash hash;
    hash.add<WideNode>(bvh.nodes);
    hash.add_value(bvh.root);
    for (const BuildPrim& prim : prims) hash.add_value(prim.id);
    return hash.value();
}

TEST(WideBvhBuilder, EveryPrimReachableOnceAndBoxesNest) {
    const Mesh mesh = test::make_triangle_soup(20000, 1);
    std::vector<BuildPrim> prims = make_triangle_build_prims(mesh);
    const WideBvh bvh = build_wide_bvh(prims, {});
    expect_valid_tree(bvh, prims, BuildSettings{}.max_leaf_size);
    EXPECT_GT(bvh.nodes.size(), 20000u / 32);
}

TEST(WideBvhBuilder, IdenticalCentroidsStillSplitIntoSmallLeaves) {
    // Every triangle the same: no SAH split separates them; index splits must.
    std::vector<BuildPrim> prims(1000, BuildPrim{{{0, 0, 0}, {1, 1, 1}}, 0, 1});
    for (std::uint32_t i = 0; i < prims.size(); ++i) prims[i].id = i;
    const WideBvh bvh = build_wide_bvh(prims, {.max_leaf_size = 2});
    expect_valid_tree(bvh, prims, 2);
}

TEST(WideBvhBuilder, GeometricSeriesKeepsDepthBounded) {
    // Positions 2^-i: SAH would peel one prim per level; the depth limit must hold.
    std::vector<BuildPrim> prims;
    for (std::uint32_t i = 0; i < 3000; ++i) {
        const float x = std::ldexp(1.0f, -int(i % 120)) * float(1 + i / 120);
        prims.push_back({{{x, 0, 0}, {x, 0, 0}}, i, 1});
    }
    const WideBvh bvh = build_wide_bvh(prims, {.max_leaf_size = 1});
    expect_valid_tree(bvh, prims, 1);
}

TEST(WideBvhBuilder, EmptyAndSinglePrim) {
    std::vector<BuildPrim> none;
    EXPECT_TRUE(build_wide_bvh(none, {}).root.is_empty());
    std::vector<BuildPrim> one{{{{0, 0, 0}, {1, 1, 1}}, 0, 1}};
    const WideBvh bvh = build_wide_bvh(one, {});
    ASSERT_TRUE(bvh.root.is_leaf());
    EXPECT_EQ(bvh.root.prim_count(), 1u);
}

TEST(WideBvhBuilder, SameTreeWithOneTwoAndEightThreads) {
    const Mesh mesh = test::make_triangle_soup(60000, 9);
    // Lift TBB's default cap (the core count) so the arena of 8 really has 8 threads.
    tbb::global_control allow_eight(tbb::global_control::max_allowed_parallelism, 8);
    std::vector<std::uint64_t> hashes;
    for (int threads : {1, 2, 8}) {
        tbb::task_arena arena(threads);
        arena.execute([&] {
            std::vector<BuildPrim> prims = make_triangle_build_prims(mesh);
            // A small threshold makes the parallel paths run even on this modest input.
            const WideBvh bvh = build_wide_bvh(prims, {.parallel_threshold = 256});
            hashes.push_back(tree_hash(bvh, prims));
        });
    }
    EXPECT_EQ(hashes[0], hashes[1]);
    EXPECT_EQ(hashes[0], hashes[2]);
}

TEST(BuildSettings, RejectsOutOfRangeValues) {
    EXPECT_THROW((BuildSettings{.bin_count = 1}.validate()), Error);
    EXPECT_THROW((BuildSettings{.max_leaf_size = 17}.validate()), Error);
    EXPECT_THROW((BuildSettings{.max_leaf_size = 0}.validate()), Error);
    EXPECT_THROW((BuildSettings{.intersection_cost = 0.0f}.validate()), Error);
    EXPECT_NO_THROW(BuildSettings{}.validate());
}

}  // namespace
}  // namespace rebraid
