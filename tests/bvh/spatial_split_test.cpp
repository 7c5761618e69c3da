#include "rebraid/bvh/spatial_split.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/spatial_split_bvh_builder.h"
#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/generators/mesh_generators.h"
#include "support/object_bvh_checks.h"
#include "support/test_scenes.h"
#include "support/thread_count_hash.h"

namespace rebraid {
namespace {

BuildSettings with_spatial_splits(float budget) {
    BuildSettings settings;
    settings.spatial_split_budget = budget;
    return settings;
}

/// Small triangles filling the unit cube, crossed by long thin slivers in random directions
/// (a sliver for every 30 small ones), as the slanted strips of CAD models: wherever an object
/// split sends a sliver, its side's box spans most of the cube.
Mesh long_triangles(std::uint32_t count, std::uint64_t seed) {
    Random random(seed);
    Mesh mesh;
    const auto random_vector = [&] {
        return Vec3f{random.next_float(-1.0f, 1.0f), random.next_float(-1.0f, 1.0f),
                     random.next_float(-1.0f, 1.0f)};
    };
    for (std::uint32_t i = 0; i < count; ++i) {
        const bool is_sliver = i % 31 == 30;
        const Vec3f centre{random.next_float01(), random.next_float01(), random.next_float01()};
        const Vec3f along = random_vector() * (is_sliver ? 0.5f : 0.02f);
        const Vec3f aside = random_vector() * (is_sliver ? 0.005f : 0.02f);
        mesh.positions.insert(mesh.positions.end(),
                              {centre - along, centre + along, centre + aside});
        mesh.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
    }
    return mesh;
}

bool holds(const BBox3f& box, Vec3f p) {
    return p.x >= box.min.x && p.y >= box.min.y && p.z >= box.min.z && p.x <= box.max.x &&
           p.y <= box.max.y && p.z <= box.max.z;
}

TEST(SpatialSplit, TriangleBoxPartsHoldEveryPointOfTheirSide) {
    Random random(17);
    std::size_t points_checked = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        std::array<Vec3f, 3> triangle;
        for (Vec3f& corner : triangle)
            corner = {random.next_float(-100.0f, 100.0f), random.next_float(-100.0f, 100.0f),
                      random.next_float(-100.0f, 100.0f)};
        BBox3f box;
        for (const Vec3f& corner : triangle) box.extend(corner);
        // Half the trials cut the box first, as a reference a spatial split already made.
        const int axis = int(random.next_u32() % 3);
        if (trial % 2 == 1) {
            const int cut = int(random.next_u32() % 3);
            box.min[cut] = random.next_float(box.min[cut], 0.5f * (box.min[cut] + box.max[cut]));
        }
        const float plane = random.next_float(box.min[axis], box.max[axis]);
        BBox3f left, right;
        split_triangle_box(triangle, box, axis, plane, left, right);
        if (!left.is_empty()) {
            EXPECT_TRUE(box.contains(left));
            EXPECT_LE(left.max[axis], plane);
        }
        if (!right.is_empty()) {
            EXPECT_TRUE(box.contains(right));
            EXPECT_GE(right.min[axis], plane);
        }
        // Points of the triangle inside the box: each in the part of its side.
        for (int sample = 0; sample < 200; ++sample) {
            float u = random.next_float01(), v = random.next_float01();
            if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
            const Vec3f p =
                triangle[0] + (triangle[1] - triangle[0]) * u + (triangle[2] - triangle[0]) * v;
            if (!holds(box, p)) continue;
            ++points_checked;
            if (p[axis] <= plane) {
                EXPECT_TRUE(holds(left, p)) << "trial " << trial;
            }
            if (p[axis] >= plane) {
                EXPECT_TRUE(holds(right, p)) << "trial " << trial;
            }
        }
    }
    EXPECT_GT(points_checked, 100000u);
}

TEST(SpatialSplitBvh, CutsLongTrianglesWithinTheBudgetAndHitsAsEmbree) {
    const Mesh mesh = long_triangles(3000, 5);
    const float budget = 0.5f;
    const ObjectBvh bvh = build_object_bvh(mesh, with_spatial_splits(budget));
    const std::size_t triangles = mesh.triangles.size();
    // Some triangles were cut, no more than the budget allows.
    EXPECT_GT(bvh.prim_ids.size(), triangles);
    EXPECT_LE(bvh.prim_ids.size(), triangles + std::size_t(float(triangles) * budget));
    ASSERT_EQ(bvh.triangles.size(), bvh.prim_ids.size());
    // Every triangle in at least one leaf, every copy the mesh's, boxes nesting, and the rows,
    // hints and counts in step (the checks of any object BVH, but for the cut triangles'
    // several leaves and their boxes, which hold only their parts).
    std::vector<int> reached(triangles, 0);
    for (std::size_t i = 0; i < bvh.prim_ids.size(); ++i) {
        ASSERT_LT(bvh.prim_ids[i], triangles);
        ++reached[bvh.prim_ids[i]];
        const auto corners = mesh.corners(bvh.prim_ids[i]);
        EXPECT_EQ(bvh.triangles[i].v0, corners[0]);
        EXPECT_EQ(bvh.triangles[i].v1, corners[1]);
        EXPECT_EQ(bvh.triangles[i].v2, corners[2]);
    }
    for (std::size_t p = 0; p < triangles; ++p) EXPECT_GE(reached[p], 1) << "prim " << p;
    for (const WideNode& node : bvh.nodes) {
        for (int slot = 0; slot < node.child_count(); ++slot) {
            if (node.children[slot].is_inner()) {
                EXPECT_TRUE(node.child_bounds(slot).contains(
                    bvh.nodes[node.children[slot].node_id()].bounds()));
            }
        }
    }
    EXPECT_TRUE(bvh.leaf_rows == make_leaf_rows(bvh.nodes, bvh.root, bvh.triangles, bvh.prim_ids));
    EXPECT_TRUE(bvh.node_prim_counts == subtree_prim_counts(bvh));
    // The parts' boxes are what a ray is culled by: the hits of Embree flat on the same mesh.
    test::expect_hits_of_embree_flat(mesh, bvh);
}

/// The cost the builder minimises, over the root's area: each inner node's area times the
/// traversal cost, each leaf's area times its references times the intersection cost.
double build_cost(const ObjectBvh& bvh, const BuildSettings& settings) {
    double cost = 0.0;
    for (const WideNode& node : bvh.nodes) {
        for (int slot = 0; slot < node.child_count(); ++slot) {
            const double area = node.child_bounds(slot).half_area();
            const NodeRef child = node.children[slot];
            cost += child.is_leaf() ? area * settings.intersection_cost * double(child.prim_count())
                                    : area * settings.traversal_cost;
        }
    }
    return cost / bvh.bounds.half_area();
}

TEST(SpatialSplitBvh, LowersTheBuildCostOfLongTriangles) {
    const Mesh mesh = long_triangles(3000, 6);
    const BuildSettings with = with_spatial_splits(0.3f), without;
    EXPECT_LT(build_cost(build_object_bvh(mesh, with), with),
              0.7 * build_cost(build_object_bvh(mesh, without), without));
}

TEST(SpatialSplitBvh, SearchesStopBelowFourThatFoundNothing) {
    // A torus of small, even triangles: its halves overlap because the surface curves, and
    // cutting triangles hardly ever beats an object split there. A way down the tree stops
    // searching after 4 empty searches in a row (without the rule: runs of 7 here, and 3.6x
    // the searches).
    const SpatialSplitSearchCounts torus =
        build_spatial_split_bvh(make_torus({.major_segment_count = 192, .minor_segment_count = 48}),
                                with_spatial_splits(0.2f))
            .search_counts;
    EXPECT_EQ(torus.longest_fruitless_run, 4u);
    EXPECT_LE(torus.cheaper, torus.searches / 20);
    EXPECT_LT(torus.searches, torus.candidates / 20);
    // The slivers' cuts pay at every level: a cheaper split found starts the run again, so the
    // searches go on all the way down.
    const SpatialSplitSearchCounts slivers =
        build_spatial_split_bvh(long_triangles(3000, 6), with_spatial_splits(0.3f)).search_counts;
    EXPECT_GT(slivers.cheaper, slivers.searches / 10);
    EXPECT_GT(slivers.searches, slivers.candidates / 2);
}

TEST(SpatialSplitBvh, SameTreeOnOneTwoAndEightThreads) {
    const Mesh mesh = long_triangles(20000, 7);
    // Small thresholds make the parallel binning (blocks of 4096 references) and hundreds
    // of subtree tasks run on this modest input.
    BuildSettings settings = with_spatial_splits(0.3f);
    settings.parallel_threshold = 256;
    settings.task_threshold = 64;
    test::expect_same_hash_on_threads(
        {1, 2, 8}, [&] { return test::structure_hash(build_object_bvh(mesh, settings)); });
}

TEST(SpatialSplitBvh, DegenerateMeshesBuildAndHitAsEmbree) {
    // One triangle; many copies of one triangle; collinear corners; a flat sheet along an
    // axis plane; all triangles at one point.
    std::vector<Mesh> meshes;
    Mesh one;
    one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 1}};
    one.triangles = {{0, 1, 2}};
    meshes.push_back(one);
    Mesh copies = one;
    for (int i = 0; i < 500; ++i) copies.triangles.push_back({0, 1, 2});
    meshes.push_back(copies);
    Mesh collinear;
    Mesh sheet;
    Mesh point;
    Random random(3);
    for (std::uint32_t i = 0; i < 400; ++i) {
        const float a = random.next_float01(), b = random.next_float01();
        collinear.positions.insert(
            collinear.positions.end(),
            {{a, a, a}, {b, b, b}, {0.5f * (a + b), 0.5f * (a + b), 0.5f * (a + b)}});
        collinear.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
        sheet.positions.insert(sheet.positions.end(),
                               {{a, 0.0f, b}, {b, 0.0f, 1.0f - a}, {1.0f - b, 0.0f, a}});
        sheet.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
        point.triangles.push_back({0, 0, 0});
    }
    point.positions = {{0.25f, 0.5f, 0.75f}};
    meshes.push_back(collinear);
    meshes.push_back(sheet);
    meshes.push_back(point);
    for (const Mesh& mesh : meshes) {
        const ObjectBvh bvh = build_object_bvh(mesh, with_spatial_splits(1.0f));
        EXPECT_GE(bvh.prim_ids.size(), mesh.triangles.size());
        EXPECT_LE(bvh.prim_ids.size(), 2 * mesh.triangles.size());
        // The same answers as Embree flat; copies of one triangle tie everywhere, and the
        // collinear and point meshes have nothing to hit.
        BBox3f around = mesh.bounds();
        around.extend(around.min - Vec3f{1, 1, 1});
        around.extend(around.max + Vec3f{1, 1, 1});
        test::Tolerance tolerance = test::tolerance_for(around);
        tolerance.max_tie_fraction = 1.0;
        tolerance.min_hit_fraction = 0.0;
        test::expect_hits_of_embree_flat(mesh, bvh, around, 4000, 11, tolerance);
    }
    const ObjectBvh empty = build_object_bvh(Mesh{}, with_spatial_splits(0.3f));
    EXPECT_TRUE(empty.prim_ids.empty());
    EXPECT_TRUE(empty.root.is_empty());
}

/// The groups of the triangles of each leaf of `built`.
std::vector<std::vector<std::uint32_t>> leaf_group_sets(const SpatialSplitBvh& built,
                                                        const std::vector<std::uint32_t>& groups) {
    std::vector<std::vector<std::uint32_t>> sets;
    const auto add = [&](NodeRef leaf) {
        std::vector<std::uint32_t>& set = sets.emplace_back();
        for (std::uint32_t i = 0; i < leaf.prim_count(); ++i)
            set.push_back(groups[built.leaf_prims[leaf.first_prim() + i]]);
    };
    if (built.tree.root.is_leaf()) add(built.tree.root);
    for (const WideNode& node : built.tree.nodes)
        for (const NodeRef child : node.children)
            if (child.is_leaf() && !child.is_empty()) add(child);
    return sets;
}

TEST(SpatialSplitBvh, LeavesNeverMixGroups) {
    // Groups interleaved in space (every third triangle), so that the SAH would gladly put
    // triangles of several groups in one leaf.
    const Mesh mesh = long_triangles(3000, 8);
    std::vector<std::uint32_t> groups(mesh.triangles.size());
    for (std::size_t i = 0; i < groups.size(); ++i) groups[i] = std::uint32_t(i % 3);
    for (const float budget : {0.0f, 0.3f}) {
        SCOPED_TRACE(budget);
        const SpatialSplitBvh ungrouped =
            build_spatial_split_bvh(mesh, with_spatial_splits(budget));
        std::size_t mixed_without = 0;
        for (const auto& set : leaf_group_sets(ungrouped, groups))
            mixed_without += std::any_of(set.begin(), set.end(),
                                         [&](std::uint32_t g) { return g != set.front(); });
        EXPECT_GT(mixed_without, 0u);  // the test means something
        const SpatialSplitBvh grouped =
            build_spatial_split_bvh(mesh, with_spatial_splits(budget), groups);
        std::vector<std::uint32_t> reached(mesh.triangles.size(), 0);
        for (const auto& set : leaf_group_sets(grouped, groups))
            for (const std::uint32_t g : set) EXPECT_EQ(g, set.front());
        for (const PrimId prim : grouped.leaf_prims) ++reached[prim];
        EXPECT_EQ(std::count(reached.begin(), reached.end(), 0u), 0);
        if (budget == 0.0f) {
            EXPECT_EQ(grouped.leaf_prims.size(), mesh.triangles.size());
        }
    }
}

TEST(SpatialSplitBvh, SettingsOutOfRangeAreRejected) {
    EXPECT_THROW(with_spatial_splits(-0.1f).validate(), Error);
    EXPECT_THROW(with_spatial_splits(4.5f).validate(), Error);
    EXPECT_THROW(with_spatial_splits(std::numeric_limits<float>::quiet_NaN()).validate(), Error);
    BuildSettings greedy = with_spatial_splits(0.3f);
    greedy.collapse = NodeCollapse::greedy;
    EXPECT_THROW(greedy.validate(), Error);
    BuildSettings greedy_without_splits;
    greedy_without_splits.collapse = NodeCollapse::greedy;
    EXPECT_THROW(build_spatial_split_bvh(long_triangles(10, 1), greedy_without_splits), Error);
    const std::vector<std::uint32_t> too_few_groups(9, 0u);
    EXPECT_THROW(
        build_spatial_split_bvh(long_triangles(10, 1), with_spatial_splits(0.3f), too_few_groups),
        Error);
    EXPECT_NO_THROW(with_spatial_splits(0.0f).validate());
    EXPECT_NO_THROW(with_spatial_splits(4.0f).validate());
}

}  // namespace
}  // namespace rebraid
