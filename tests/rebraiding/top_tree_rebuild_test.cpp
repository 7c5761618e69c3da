#include "rebraid/rebraiding/top_tree_rebuild.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/instanced_accel.h"
#include "rebraid/top_level/two_level_builder.h"
#include "support/reachability.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

/// `count` items with random boxes, item k naming instance k and node k.
TopLevelBvh random_items(std::uint32_t count, std::uint64_t seed) {
    Random random(seed);
    TopLevelBvh top;
    for (std::uint32_t k = 0; k < count; ++k) {
        const Vec3f corner{random.next_float(-10.0f, 10.0f), random.next_float(-10.0f, 10.0f),
                           random.next_float(-10.0f, 10.0f)};
        const Vec3f size{random.next_float(0.0f, 3.0f), random.next_float(0.0f, 3.0f),
                         random.next_float(0.0f, 3.0f)};
        top.items.push_back({InstanceId(k), NodeRef::inner(k)});
        top.item_bounds.push_back(BBox3f{corner, corner + size});
    }
    return top;
}

/// Item positions below `ref`, each child box checked to hold the boxes of the items below it.
void collect_positions(const TopLevelBvh& top, NodeRef ref, const BBox3f& box,
                       std::vector<int>& reached) {
    if (ref.is_leaf()) {
        for (std::uint32_t p = ref.first_prim(); p < ref.first_prim() + ref.prim_count(); ++p) {
            ASSERT_LT(p, reached.size());
            ++reached[p];
            EXPECT_TRUE(box.contains(top.item_bounds[p])) << "item at " << p;
        }
        return;
    }
    const WideNode& node = top.nodes.at(ref.node_id());
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        const BBox3f child = node.child_bounds(slot);
        EXPECT_TRUE(box.contains(child));
        collect_positions(top, node.children[slot], child, reached);
    }
}

TEST(TopTreeRebuild, KeepsEachItemWithItsBoxAndReachesEachOnce) {
    for (const NodeCollapse collapse : {NodeCollapse::greedy, NodeCollapse::optimal}) {
        SCOPED_TRACE(int(collapse));
        TopLevelBvh top = random_items(500, 11);
        const TopLevelBvh before = top;
        std::vector<std::uint32_t> primitives;
        for (std::uint32_t k = 0; k < 500; ++k) primitives.push_back(1 + (k * 37) % 3000);
        BuildSettings settings{.max_leaf_size = 1, .collapse = collapse};
        rebuild_top_tree(top, primitives, settings);
        ASSERT_EQ(top.items.size(), before.items.size());
        ASSERT_TRUE(top.root.is_inner());
        std::vector<int> moved_to(500, -1);
        for (std::size_t p = 0; p < top.items.size(); ++p) {
            const InstanceId k = top.items[p].instance_id;
            ASSERT_LT(k, 500u);
            EXPECT_EQ(moved_to[k], -1) << "item " << k << " twice";
            moved_to[k] = int(p);
            EXPECT_EQ(top.items[p].object_node, NodeRef::inner(k));
            EXPECT_EQ(top.item_bounds[p], before.item_bounds[k]);
        }
        // The items did move: a tree over random boxes is not in their input order.
        std::size_t in_place = 0;
        for (std::uint32_t k = 0; k < 500; ++k) in_place += moved_to[k] == int(k);
        EXPECT_LT(in_place, 250u);
        std::vector<int> reached(top.items.size(), 0);
        collect_positions(top, top.root, top.bounds, reached);
        for (std::size_t p = 0; p < reached.size(); ++p) EXPECT_EQ(reached[p], 1) << p;
        // The plain top builder over the same items and boxes, each weighted by
        // rebuilt_tree_weight of its primitives, builds the same tree.
        std::vector<std::uint32_t> weights;
        for (const std::uint32_t count : primitives) weights.push_back(rebuilt_tree_weight(count));
        const TopLevelBvh plain =
            build_top_level_over_items(before.items, before.item_bounds, weights, settings);
        ASSERT_EQ(plain.nodes.size(), top.nodes.size());
        EXPECT_EQ(
            std::memcmp(plain.nodes.data(), top.nodes.data(), top.nodes.size() * sizeof(WideNode)),
            0);
        EXPECT_EQ(plain.item_bounds, top.item_bounds);
    }
}

TEST(TopTreeRebuild, WeighsABRefByTheLogarithmOfItsPrimitives) {
    static_assert(rebuilt_tree_weight(0) == 1 && rebuilt_tree_weight(1) == 1);
    EXPECT_EQ(rebuilt_tree_weight(2), 2u);
    EXPECT_EQ(rebuilt_tree_weight(3), 2u);
    EXPECT_EQ(rebuilt_tree_weight(127), 7u);
    EXPECT_EQ(rebuilt_tree_weight(128), 8u);
    EXPECT_EQ(rebuilt_tree_weight(3'000'000), 22u);
}

TEST(TopTreeRebuild, RejectsPerItemArraysOfAnotherLength) {
    TopLevelBvh top = random_items(10, 3);
    const std::vector<std::uint32_t> primitives(9, 1);
    EXPECT_THROW(rebuild_top_tree(top, primitives, {.max_leaf_size = 1}), Error);
}

TEST(TopTreeRebuild, ReBraidedTopsHoldTheSameItemsWithAndWithoutIt) {
    // Overlapping instances open; the rebuilt tree must hold exactly the BRefs opening chose,
    // each reached once by the traversal's walk.
    const Scene scene = test::make_overlap_scene(200, 3);
    const std::vector<ObjectBvh> bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    RebraidSettings as_opened;
    as_opened.rebuild_tree = false;
    const RebraidBuild grown = build_rebraid(scene, bvhs, as_opened);
    const RebraidBuild rebuilt = build_rebraid(scene, bvhs, {});
    ASSERT_GT(grown.opened, 0u);
    EXPECT_EQ(rebuilt.opened, grown.opened);
    EXPECT_EQ(rebuilt.brefs, grown.brefs);
    const auto key = [](const TopLevelItem& item) {
        return (std::uint64_t(item.instance_id) << 32) | item.object_node.bits();
    };
    std::vector<std::uint64_t> a, b;
    for (const TopLevelItem& item : grown.top.items) a.push_back(key(item));
    for (const TopLevelItem& item : rebuilt.top.items) b.push_back(key(item));
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b);
    EXPECT_NE(grown.top.nodes.size(), 0u);
    const InstancedAccel accel(scene, bvhs, RebraidBuild(rebuilt).top, {});
    test::expect_each_reached_once(test::reach_counts(scene, accel));
}

}  // namespace
}  // namespace rebraid
