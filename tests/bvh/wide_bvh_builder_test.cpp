#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/bvh/object_bvh_builder.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/grow_wide_subtree.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/parallel_partition.h"
#include "rebraid/bvh/wide_tree_grower.h"
#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/core/structure_hash.h"
#include "support/test_scenes.h"

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

/// Largest child count of any node of `bvh`.
int widest_node(const WideBvh& bvh) {
    int widest = 0;
    for (const WideNode& node : bvh.nodes) widest = std::max(widest, node.child_count());
    return widest;
}

TEST(WideBvhBuilder, MaxChildrenNarrowsNodesAndFillNodesFillsThem) {
    const Mesh mesh = test::make_triangle_soup(20000, 2);
    for (std::uint32_t width : {2u, 4u, 8u}) {
        std::vector<BuildPrim> prims = make_triangle_build_prims(mesh);
        const WideBvh bvh = build_wide_bvh(prims, {.max_children = width});
        expect_valid_tree(bvh, prims, BuildSettings{}.max_leaf_size);
        EXPECT_EQ(widest_node(bvh), int(width));
    }
    // Full nodes: fewer, fuller nodes than when children the binary SAH test would keep as
    // leaves stay unsplit.
    std::vector<BuildPrim> full_prims = make_triangle_build_prims(mesh);
    std::vector<BuildPrim> sparse_prims = full_prims;
    const WideBvh full =
        build_wide_bvh(full_prims, {.fill_nodes = true, .collapse = NodeCollapse::greedy});
    const WideBvh sparse =
        build_wide_bvh(sparse_prims, {.fill_nodes = false, .collapse = NodeCollapse::greedy});
    expect_valid_tree(full, full_prims, BuildSettings{}.max_leaf_size);
    expect_valid_tree(sparse, sparse_prims, BuildSettings{}.max_leaf_size);
    auto mean_children = [](const WideBvh& bvh) {
        double sum = 0;
        for (const WideNode& node : bvh.nodes) sum += node.child_count();
        return sum / double(bvh.nodes.size());
    };
    EXPECT_GT(mean_children(full), mean_children(sparse));
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
            // Small thresholds make every parallel path run even on this modest input:
            // multi-block binning and partitions (ranges of several 4096-prim blocks) and
            // hundreds of subtree tasks.
            const WideBvh bvh =
                build_wide_bvh(prims, {.parallel_threshold = 256, .task_threshold = 64});
            expect_valid_tree(bvh, prims, BuildSettings{}.max_leaf_size);
            hashes.push_back(tree_hash(bvh, prims));
        });
    }
    EXPECT_EQ(hashes[0], hashes[1]);
    EXPECT_EQ(hashes[0], hashes[2]);
}

/// Hash of a tree's shape independent of node numbering: child boxes and leaf contents in
/// depth-first order.
void add_shape(StructureHash& hash, const WideBvh& bvh, std::span<const BuildPrim> prims,
               NodeRef ref) {
    hash.add_value(ref.is_leaf());
    if (ref.is_leaf()) {
        for (std::uint32_t i = ref.first_prim(); i < ref.first_prim() + ref.prim_count(); ++i)
            hash.add_value(prims[i].id);
        return;
    }
    const WideNode& node = bvh.nodes[ref.node_id()];
    for (int i = 0; i < node.child_count(); ++i) {
        hash.add_value(node.child_bounds(i));
        add_shape(hash, bvh, prims, node.children[i]);
    }
}

// The greedy collapse numbers the subtrees that tasks built after their parents' other
// nodes, so the task threshold changes the numbering (never the shape); the optimal collapse
// numbers every node depth first once the whole tree is known, so nothing changes.
TEST(WideBvhBuilder, TaskThresholdChangesNumberingOnly) {
    const Mesh mesh = test::make_triangle_soup(20000, 5);
    for (NodeCollapse collapse : {NodeCollapse::greedy, NodeCollapse::optimal}) {
        std::vector<std::uint64_t> shapes, hashes;
        for (std::size_t task_threshold : {std::size_t(16), std::size_t(1) << 30}) {
            std::vector<BuildPrim> prims = make_triangle_build_prims(mesh);
            const WideBvh bvh =
                build_wide_bvh(prims, {.task_threshold = task_threshold, .collapse = collapse});
            StructureHash shape;
            add_shape(shape, bvh, prims, bvh.root);
            shapes.push_back(shape.value());
            hashes.push_back(tree_hash(bvh, prims));
        }
        EXPECT_EQ(shapes[0], shapes[1]);
        if (collapse == NodeCollapse::greedy)
            EXPECT_NE(hashes[0], hashes[1]) << "one task builds all: expected another numbering";
        else
            EXPECT_EQ(hashes[0], hashes[1]);
    }
}

/// The SAH's node cost of a tree: the half areas of its inner nodes' boxes.
double node_cost(const WideBvh& bvh, NodeRef ref, const BBox3f& box) {
    if (!ref.is_inner()) return 0.0;
    const WideNode& node = bvh.nodes[ref.node_id()];
    double cost = box.half_area();
    for (int i = 0; i < node.child_count(); ++i)
        cost += node_cost(bvh, node.children[i], node.child_bounds(i));
    return cost;
}

/// The leaves of a tree as (first prim's id, count), sorted.
std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves_of(const WideBvh& bvh,
                                                               std::span<const BuildPrim> prims) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves;
    std::vector<NodeRef> stack{bvh.root};
    while (!stack.empty()) {
        const NodeRef ref = stack.back();
        stack.pop_back();
        if (ref.is_leaf()) {
            leaves.emplace_back(prims[ref.first_prim()].id, ref.prim_count());
            continue;
        }
        const WideNode& node = bvh.nodes[ref.node_id()];
        for (int i = 0; i < node.child_count(); ++i) stack.push_back(node.children[i]);
    }
    std::sort(leaves.begin(), leaves.end());
    return leaves;
}

// Both collapses cut the same binary tree of splits into wide nodes: the same leaves, and the
// optimal cut's node cost is never above the greedy one's (and below it on these inputs, at
// every node width and leaf size tried).
TEST(WideBvhBuilder, OptimalCollapseKeepsTheLeavesAndLowersTheNodeCost) {
    for (std::uint64_t seed : {3u, 4u}) {
        const Mesh mesh = test::make_triangle_soup(5000, seed);
        for (std::uint32_t max_leaf : {1u, 8u})
            for (std::uint32_t width : {4u, 8u}) {
                SCOPED_TRACE("seed " + std::to_string(seed) + ", leaves of " +
                             std::to_string(max_leaf) + ", width " + std::to_string(width));
                std::vector<BuildPrim> greedy_prims = make_triangle_build_prims(mesh);
                std::vector<BuildPrim> optimal_prims = greedy_prims;
                const BuildSettings greedy{.max_leaf_size = max_leaf,
                                           .collapse = NodeCollapse::greedy,
                                           .max_children = width};
                BuildSettings optimal = greedy;
                optimal.collapse = NodeCollapse::optimal;
                const WideBvh a = build_wide_bvh(greedy_prims, greedy);
                const WideBvh b = build_wide_bvh(optimal_prims, optimal);
                expect_valid_tree(b, optimal_prims, max_leaf);
                EXPECT_LE(widest_node(b), int(width));
                EXPECT_EQ(leaves_of(a, greedy_prims), leaves_of(b, optimal_prims));
                EXPECT_LT(node_cost(b, b.root, b.bounds), node_cost(a, a.root, a.bounds));
            }
    }
}

std::vector<BuildPrim> soup_prims(std::uint32_t count, std::uint64_t seed) {
    return make_triangle_build_prims(test::make_triangle_soup(count, seed));
}

/// RangeInfo fields compared exactly (both come from min/max and integer sums).
void expect_same_info(const RangeInfo& a, const RangeInfo& b) {
    EXPECT_EQ(a.bounds, b.bounds);
    EXPECT_EQ(a.centroid_bounds, b.centroid_bounds);
    EXPECT_EQ(a.weight, b.weight);
    EXPECT_EQ(a.count, b.count);
}

/// Checks a partition result against the split's own predicate and compute_range_info.
void expect_partitioned(std::span<const BuildPrim> prims, const BinnedSplit& split,
                        const SplitResult& result, std::size_t expected_left) {
    ASSERT_EQ(result.left_count, expected_left);
    for (std::size_t i = 0; i < prims.size(); ++i)
        ASSERT_EQ(split.goes_left(prims[i]), i < result.left_count) << "prim slot " << i;
    expect_same_info(result.left, compute_range_info(prims.first(result.left_count), 1u << 30));
    expect_same_info(result.right, compute_range_info(prims.subspan(result.left_count), 1u << 30));
}

std::vector<std::uint32_t> sorted_ids(std::span<const BuildPrim> prims) {
    std::vector<std::uint32_t> ids;
    for (const BuildPrim& prim : prims) ids.push_back(prim.id);
    std::sort(ids.begin(), ids.end());
    return ids;
}

/// A range of indices as WideTreeGrower and grow_wide_subtree see it, split a third of the
/// way in (lopsided subtrees of every size), a leaf at three or fewer.
struct IndexRange {
    std::uint32_t begin = 0, end = 0;
    bool is_leaf = false;
    float area() const { return float(end - begin); }
    BBox3f bounds() const { return {{float(begin), 0, 0}, {float(end), 1, 1}}; }
    std::size_t size() const { return end - begin; }
};

struct IndexRangePolicy {
    static IndexRange make(std::uint32_t begin, std::uint32_t end) {
        return {begin, end, end - begin <= 3};
    }
    std::array<IndexRange, 2> split(const IndexRange& c, bool) const {
        const std::uint32_t mid = c.begin + std::max<std::uint32_t>(1, (c.end - c.begin) / 3);
        return {make(c.begin, mid), make(mid, c.end)};
    }
    NodeRef make_leaf(const IndexRange& c) const { return NodeRef::leaf(c.begin, c.end - c.begin); }
};

TEST(WideTreeGrower, NumbersNodesAsTheSerialRecursionForAnyTaskAndPlacementSplit) {
    // The grower builds large subtrees as tasks into chunks and numbers them in one placement
    // pass, itself split into tasks by subtree size: neither split may change a bit of the
    // node array grow_wide_subtree makes on one thread.
    tbb::global_control allow_four(tbb::global_control::max_allowed_parallelism, 4);
    const IndexRangePolicy policy;
    const IndexRange root = IndexRangePolicy::make(0, 20000);
    constexpr std::size_t kLayoutThreshold = 500;
    std::vector<WideNode> expected;
    const NodeRef expected_root = grow_wide_subtree(policy, root, 0, kLayoutThreshold, expected);
    ASSERT_EQ(expected_root, NodeRef::inner(0));
    ASSERT_GT(expected.size(), 1000u);
    for (const std::size_t task_threshold : {std::size_t(1) << 30, std::size_t(64), std::size_t(7)})
        for (const std::uint32_t place_task_nodes : {1u << 30, 100u, 1u}) {
            SCOPED_TRACE(testing::Message() << task_threshold << " " << place_task_nodes);
            const WideTreeGrower<IndexRangePolicy, IndexRange> grower(
                policy, kLayoutThreshold, task_threshold, place_task_nodes);
            std::vector<WideNode> nodes;
            EXPECT_EQ(grower.grow(root, nodes), expected_root);
            ASSERT_EQ(nodes.size(), expected.size());
            EXPECT_EQ(std::memcmp(nodes.data(), expected.data(), nodes.size() * sizeof(WideNode)),
                      0);
        }
}

TEST(BinnedSplit, PartitionsAgreeWithGoesLeftAndMeasureBothSides) {
    const std::vector<BuildPrim> input = soup_prims(30000, 3);
    const RangeInfo info = compute_range_info(input, 1024);
    expect_same_info(info, compute_range_info(input, 1u << 30));  // parallel == serial
    const BinnedSplit split = find_binned_split(input, info, {});
    ASSERT_TRUE(split.is_valid());
    const auto expected_left = std::size_t(std::count_if(
        input.begin(), input.end(), [&](const BuildPrim& p) { return split.goes_left(p); }));
    ASSERT_GT(expected_left, 0u);
    ASSERT_LT(expected_left, input.size());

    std::vector<std::vector<std::uint32_t>> left_ids;
    // Serial and parallel (several blocks), out of place, in place through scratch, and in
    // place without scratch.
    for (std::size_t threshold : {std::size_t(1) << 30, std::size_t(64)}) {
        std::vector<BuildPrim> out(input.size());
        const SplitResult into = apply_binned_split_into(input, out, split, threshold);
        expect_partitioned(out, split, into, expected_left);
        left_ids.push_back(sorted_ids(std::span<const BuildPrim>(out).first(into.left_count)));

        std::vector<BuildPrim> prims = input, scratch(input.size());
        expect_partitioned(prims, split, apply_binned_split(prims, split, scratch, threshold),
                           expected_left);
    }
    std::vector<BuildPrim> prims = input;
    expect_partitioned(prims, split, apply_binned_split(prims, split, {}, 1u << 30), expected_left);
    EXPECT_EQ(left_ids[0], left_ids[1]);
}

TEST(ParallelPartition, ParallelPathIsStable) {
    std::vector<int> values(50000);
    std::iota(values.begin(), values.end(), 0);
    Random random(11);
    for (std::uint32_t i = std::uint32_t(values.size()); i > 1; --i)
        std::swap(values[i - 1], values[random.next_below(i)]);
    auto is_small = [](int v) { return v % 7 < 3; };
    std::vector<int> expected = values;
    std::stable_partition(expected.begin(), expected.end(), is_small);
    const std::size_t left = parallel_partition(std::span<int>(values), is_small, 100);
    EXPECT_EQ(left, std::size_t(std::count_if(expected.begin(), expected.end(), is_small)));
    EXPECT_EQ(values, expected);
}

TEST(BinnedSplit, SmallRangesGetTheCheapestPlaneSplit) {
    Random random(21);
    int splits_checked = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const std::uint32_t n = 2 + random.next_below(kMaxExactSplitPrims - 1);
        std::vector<BuildPrim> prims(n);
        for (std::uint32_t i = 0; i < n; ++i) {
            // Coarse positions, so that some centroids coincide on some axes.
            const Vec3f p{float(random.next_below(4)), float(random.next_below(4)),
                          float(random.next_below(4))};
            const Vec3f size{random.next_float(0, 2), random.next_float(0, 2),
                             random.next_float(0, 2)};
            prims[i] = {{p, p + size}, i, 1 + random.next_below(3)};
        }
        // Brute force: every assignment of the prims to two non-empty sides whose centroids
        // an axis-aligned plane separates.
        double cheapest = 1e30;
        for (std::uint32_t mask = 1; mask + 1 < (1u << n); ++mask) {
            BBox3f sides[2], centres[2];
            double weights[2] = {0, 0};
            for (std::uint32_t i = 0; i < n; ++i) {
                const int side = (mask >> i) & 1;
                sides[side].extend(prims[i].bounds);
                centres[side].extend(prims[i].centroid());
                weights[side] += prims[i].weight;
            }
            bool separated = false;
            for (int a = 0; a < 3; ++a)
                separated = separated || centres[0].max[a] < centres[1].min[a] ||
                            centres[1].max[a] < centres[0].min[a];
            if (separated)
                cheapest = std::min(cheapest, double(sides[0].half_area()) * weights[0] +
                                                  double(sides[1].half_area()) * weights[1]);
        }
        const RangeInfo info = compute_range_info(prims, 64);
        const BinnedSplit split = find_binned_split(prims, info, {});
        ASSERT_EQ(split.is_valid(), cheapest < 1e30);
        if (!split.is_valid()) continue;
        ++splits_checked;
        EXPECT_TRUE(split.is_exact());
        EXPECT_NEAR(split.cost, cheapest, 1e-5 * cheapest);

        std::vector<BuildPrim> applied = prims;
        const SplitResult result = apply_binned_split(applied, split, {}, 1u << 30);
        const auto expected_left = std::size_t(std::count_if(
            prims.begin(), prims.end(), [&](const BuildPrim& p) { return split.goes_left(p); }));
        expect_partitioned(applied, split, result, expected_left);
        EXPECT_EQ(sorted_ids(applied), sorted_ids(prims));
    }
    EXPECT_GT(splits_checked, 300);
}

TEST(BuildSettings, RejectsOutOfRangeValues) {
    EXPECT_THROW((BuildSettings{.bin_count = 1}.validate()), Error);
    EXPECT_THROW((BuildSettings{.max_leaf_size = 17}.validate()), Error);
    EXPECT_THROW((BuildSettings{.max_leaf_size = 0}.validate()), Error);
    EXPECT_THROW((BuildSettings{.intersection_cost = 0.0f}.validate()), Error);
    EXPECT_THROW((BuildSettings{.task_threshold = 0}.validate()), Error);
    EXPECT_THROW((BuildSettings{.prims_per_bin = 0}.validate()), Error);
    EXPECT_THROW((BuildSettings{.max_children = 1}.validate()), Error);
    EXPECT_THROW((BuildSettings{.max_children = 9}.validate()), Error);
    EXPECT_NO_THROW(BuildSettings{}.validate());
}

}  // namespace
}  // namespace rebraid
