// The pre-arranged leaf rows the SIMD triangle tests read (rebraid/bvh/leaf_rows.h): their
// layout, and that every way of making or changing an object BVH keeps them in step.

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <set>
#include <vector>

#include "rebraid/bvh/leaf_row_hints.h"
#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/error.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/generators/world_space_objects.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/hit_comparison.h"

namespace rebraid {
namespace {

/// Every leaf below `ref`, in no particular order.
void collect_leaves(const ObjectBvh& bvh, NodeRef ref, std::vector<NodeRef>& leaves) {
    if (ref.is_leaf()) {
        leaves.push_back(ref);
        return;
    }
    for (const NodeRef child : bvh.nodes[ref.node_id()].children)
        if (!child.is_empty()) collect_leaves(bvh, child, leaves);
}

TEST(LeafRows, HoldEachLeafsCornersAxisByAxisThenItsPrimIdsAfterPadding) {
    BuildSettings settings;
    settings.max_leaf_size = 8;
    const Mesh mesh = make_torus_knot();
    const ObjectBvh bvh = build_object_bvh(mesh, settings);
    ASSERT_EQ(bvh.leaf_rows.size(), 10 * bvh.triangles.size() + 2 * kLeafRowPadding);
    std::vector<NodeRef> leaves;
    collect_leaves(bvh, bvh.root, leaves);
    std::size_t checked = 0, wider_than_one = 0;
    for (const NodeRef leaf : leaves) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        wider_than_one += count > 1;
        for (std::uint32_t i = 0; i < count; ++i) {
            const TriangleVerts& t = bvh.triangles[first + i];
            const Vec3f corners[3] = {t.v0, t.v1, t.v2};
            for (int c = 0; c < 3; ++c)
                for (int a = 0; a < 3; ++a) {
                    const float row_value =
                        bvh.leaf_rows[kLeafRowPadding + 10 * first + (3 * c + a) * count + i];
                    ASSERT_EQ(row_value, corners[c][a]) << "leaf at " << first << ", triangle " << i
                                                        << ", corner " << c << ", axis " << a;
                }
            // Row 9: the primID's bits.
            const float id_value = bvh.leaf_rows[kLeafRowPadding + 10 * first + 9 * count + i];
            ASSERT_EQ(std::bit_cast<PrimId>(id_value), bvh.prim_ids[first + i])
                << "leaf at " << first << ", triangle " << i;
            ++checked;
        }
    }
    EXPECT_EQ(checked, bvh.triangles.size());
    EXPECT_GT(wider_than_one, 0u);  // the stride is a leaf's count, not always 1
    for (std::uint32_t p = 0; p < kLeafRowPadding; ++p) {
        EXPECT_EQ(bvh.leaf_rows[p], 0.0f);
        EXPECT_EQ(bvh.leaf_rows[bvh.leaf_rows.size() - 1 - p], 0.0f);
    }
}

TEST(LeafRows, RewritingInPlaceKeepsTheBufferAndRefusesAWrongSize) {
    const ObjectBvh bvh = build_object_bvh(make_torus_knot(), {});
    std::vector<float> rows(bvh.leaf_rows.size(), -1.0f);
    const float* address = rows.data();
    rewrite_leaf_rows(bvh.nodes, bvh.root, bvh.triangles, bvh.prim_ids, rows);
    EXPECT_EQ(rows.data(), address);
    for (std::size_t i = kLeafRowPadding; i < rows.size() - kLeafRowPadding; ++i)
        ASSERT_EQ(rows[i], bvh.leaf_rows[i]) << i;
    std::vector<float> short_rows(rows.size() - 1);
    EXPECT_THROW(rewrite_leaf_rows(bvh.nodes, bvh.root, bvh.triangles, bvh.prim_ids, short_rows),
                 Error);
}

// Each inner child's hint names the rows of its first leaf child and of the leaf children that
// follow it in leaf order, in whole cache lines up to the cap; children that are leaves, empty
// or without leaf children have none.
TEST(LeafRows, HintsNameTheRowsOfEachInnerChildsLeafChildren) {
    const ObjectBvh bvh = build_object_bvh(make_torus_knot(), {});
    std::size_t hinted = 0, capped = 0;
    for (const WideNode& node : bvh.nodes)
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const std::uint32_t hint = node.leaf_row_hints[slot];
            const NodeRef child = node.children[slot];
            if (!child.is_inner()) {
                EXPECT_EQ(hint, 0u);
                continue;
            }
            std::uint32_t first = 0, end = 0;
            for (const NodeRef grandchild : bvh.nodes[child.node_id()].children) {
                if (!grandchild.is_leaf()) continue;
                if (end == 0) {
                    first = grandchild.first_prim();
                    end = first + grandchild.prim_count();
                } else if (grandchild.first_prim() == end) {
                    end += grandchild.prim_count();
                } else {
                    break;
                }
            }
            if (end == 0) {
                EXPECT_EQ(hint, 0u);
                continue;
            }
            ++hinted;
            EXPECT_EQ(hint & NodeRef::kMaxFirst, first);
            const std::uint32_t lines = hint >> kLeafRowHintLineShift;
            const std::uint32_t bytes = (end - first) * kRowFloatsPerTriangle * sizeof(float);
            EXPECT_GE(lines, 1u);
            EXPECT_LE(lines, kMaxLeafRowHintLines);
            if (lines < kMaxLeafRowHintLines)
                EXPECT_GE(64 * lines, bytes);  // every row, from anywhere in the first line
            else
                ++capped;
        }
    EXPECT_GT(hinted, bvh.nodes.size() / 2);
    EXPECT_LT(capped, hinted);
}

/// Hits equal to the last bit, and the same occlusion answers.
void expect_identical(const test::AccelAnswers& a, const test::AccelAnswers& b) {
    ASSERT_EQ(a.hits.size(), b.hits.size());
    std::size_t hits = 0, differences = 0;
    for (std::size_t i = 0; i < a.hits.size(); ++i) {
        const Hit& x = a.hits[i];
        const Hit& y = b.hits[i];
        hits += x.is_hit();
        const bool same = std::bit_cast<std::uint32_t>(x.t) == std::bit_cast<std::uint32_t>(y.t) &&
                          std::bit_cast<std::uint32_t>(x.u) == std::bit_cast<std::uint32_t>(y.u) &&
                          std::bit_cast<std::uint32_t>(x.v) == std::bit_cast<std::uint32_t>(y.v) &&
                          x.instance_id == y.instance_id && x.prim_id == y.prim_id &&
                          a.occluded[i] == b.occluded[i];
        if (!same && ++differences <= 5) ADD_FAILURE() << "ray " << i << " answers differ";
    }
    EXPECT_EQ(differences, 0u);
    EXPECT_GT(hits, a.hits.size() / 10);  // enough hits for the comparison to mean something
}

// Items of a top level that name part of an object BVH leaf (leaf references that are no
// leaf of their object BVH).
std::size_t count_partial_leaf_items(const InstancedAccel& accel) {
    std::vector<std::set<std::uint32_t>> leaves(accel.object_bvhs().size());
    for (std::size_t mesh = 0; mesh < leaves.size(); ++mesh) {
        const ObjectBvh& bvh = accel.object_bvhs()[mesh];
        if (bvh.root.is_leaf()) leaves[mesh].insert(bvh.root.bits());
        for (const WideNode& node : bvh.nodes)
            for (const NodeRef child : node.children)
                if (child.is_leaf()) leaves[mesh].insert(child.bits());
    }
    std::size_t partial = 0;
    for (const TopLevelItem& item : accel.top_level().items) {
        const std::uint32_t mesh = accel.instance_meshes()[item.instance_id];
        if (item.object_node.is_leaf() && !leaves[mesh].contains(item.object_node.bits()))
            ++partial;
    }
    return partial;
}

// The kernels read the rows where they exist and the per-triangle corners where not (and for
// re-braided BRefs of single triangles, which start inside a leaf: TopLevelBvh::
// has_partial_leaves): both give the same answers, bit for bit, for the flat, two-level and
// re-braided structures, with the kernels of every level this build and CPU run (the
// portable ones read the corners either way).
template <class Structure>
void expect_same_with_and_without_rows(Structure& with_rows, Structure& without_rows,
                                       const std::vector<Ray>& rays) {
    for (SimdLevel level : runnable_simd_levels()) {
        SCOPED_TRACE(simd_level_name(level));
        with_rows.set_simd_level(level);
        without_rows.set_simd_level(level);
        expect_identical(test::trace_all(with_rows, rays), test::trace_all(without_rows, rays));
    }
}

TEST(LeafRows, KernelsAnswerTheSameWithAndWithoutThem) {
    const Scene scene = make_default_scene();
    const std::vector<Ray> rays = generate_random_rays(scene.bounds(), 20000, 11);
    BuildSettings with_rows, without_rows;
    without_rows.pre_arranged_leaves = false;
    {
        FlatAccel a(scene, with_rows), b(scene, without_rows);
        EXPECT_FALSE(a.bvh().leaf_rows.empty());
        EXPECT_TRUE(b.bvh().leaf_rows.empty());
        expect_same_with_and_without_rows(a, b, rays);
    }
    RebraidSettings single_triangles;
    single_triangles.open_threshold = 0.0f;
    single_triangles.budget_factor = 1000.0f;
    single_triangles.open_leaves = true;
    single_triangles.opening_rule = OpeningRule::extent;
    for (const RebraidSettings& rebraid : {RebraidSettings{}, single_triangles}) {
        InstancedAccel a = build_rebraid_accel(scene, own_object_bvh_builder(with_rows), rebraid);
        InstancedAccel b =
            build_rebraid_accel(scene, own_object_bvh_builder(without_rows), rebraid);
        // Leaf items of the default rules are whole leaves, which the rows serve; opened
        // leaves are marked, and their items read the corners.
        EXPECT_EQ(a.top_level().has_partial_leaves, rebraid.open_leaves);
        if (rebraid.open_leaves)
            EXPECT_GT(count_partial_leaf_items(a), 100u);
        else
            EXPECT_EQ(count_partial_leaf_items(a), 0u);
        expect_same_with_and_without_rows(a, b, rays);
    }
    InstancedAccel a = build_two_level_accel(scene, own_object_bvh_builder(with_rows));
    InstancedAccel b = build_two_level_accel(scene, own_object_bvh_builder(without_rows));
    expect_same_with_and_without_rows(a, b, rays);
}

TEST(LeafRows, AskedForAheadOnlyWhereTheStructuresRowsOutgrowTheCaches) {
    const Scene scene = make_default_scene();
    // The flat BVH's rows (1.5 M triangles) are far beyond kLeafRowPrefetchMinBytes; the
    // re-braided structure's six object BVHs together are not.
    const FlatAccel flat(scene);
    EXPECT_TRUE(ObjectBvhView(flat.bvh()).prefetches_rows);
    const InstancedAccel rebraided = build_rebraid_accel(scene);
    for (const ObjectBvhView& view : rebraided.object_views()) EXPECT_FALSE(view.prefetches_rows);
    // One mesh per instance: no object BVH alone reaches the threshold, all of them together
    // do, and the structure decides for all.
    Scene copies;
    for (const Instance& instance : scene.instances) {
        copies.meshes.push_back(scene.meshes[instance.mesh_id]);
        copies.instances.push_back({MeshId(copies.meshes.size() - 1), instance.object_to_world});
    }
    const InstancedAccel two_level = build_two_level_accel(copies);
    std::uint64_t row_floats = 0;
    for (const ObjectBvh& bvh : two_level.object_bvhs()) {
        EXPECT_FALSE(ObjectBvhView(bvh).prefetches_rows);
        row_floats += bvh.leaf_rows.size();
    }
    EXPECT_GE(row_floats * sizeof(float), kLeafRowPrefetchMinBytes);
    for (const ObjectBvhView& view : two_level.object_views()) EXPECT_TRUE(view.prefetches_rows);

    // The same meshes in world space, merged into the top level: its copied nodes ask for
    // rows too (MergedTopLevel::rows_prefetch_from), for the same hits as entering the items,
    // which ask for them in their object BVHs' traversals (the helper compares any two
    // structures that must answer alike).
    const Scene world = bake_instances_into_world_space(copies);
    RebraidSettings merge, no_merge;
    no_merge.merge_world_space = false;
    InstancedAccel merged = build_rebraid_accel(world, own_object_bvh_builder(), merge);
    InstancedAccel entered = build_rebraid_accel(world, own_object_bvh_builder(), no_merge);
    ASSERT_FALSE(merged.merged_top_level().empty());
    EXPECT_EQ(merged.merged_top_level().rows_prefetch_from,
              merged.merged_top_level().first_object_node);
    EXPECT_TRUE(entered.merged_top_level().empty());
    const std::vector<Ray> rays = generate_random_rays(world.bounds(), 20000, 12);
    expect_same_with_and_without_rows(merged, entered, rays);
}

}  // namespace
}  // namespace rebraid
