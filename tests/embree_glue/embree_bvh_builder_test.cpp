// Builder 2: Embree's rtcBuildBVH building the project's wide node layout. Tree validity,
// determinism, errors, hits of two-level structures over Embree-built object BVHs against
// Embree's own flat scene, and SAH next to the project's builder.
#include "embree_glue/reference/embree_bvh_builder.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/core/structure_hash.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/top_level/bvh_stats.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/hit_comparison.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

using glue::EmbreeBuildQuality;
using glue::EmbreeBvhBuilderSettings;

/// The Embree configurations every test runs: each quality, and high with spatial splits.
struct NamedSettings {
    std::string name;
    EmbreeBvhBuilderSettings settings;
};

std::vector<NamedSettings> embree_configurations() {
    return {
        {"low", {.quality = EmbreeBuildQuality::low}},
        {"medium", {.quality = EmbreeBuildQuality::medium}},
        {"high", {.quality = EmbreeBuildQuality::high}},
        {"high+splits", {.quality = EmbreeBuildQuality::high, .can_split_triangles = true}},
    };
}

bool has_splits(const EmbreeBvhBuilderSettings& settings) {
    return settings.quality == EmbreeBuildQuality::high && settings.can_split_triangles;
}

BBox3f triangle_box(const TriangleVerts& tri) {
    BBox3f box;
    for (Vec3f corner : {tri.v0, tri.v1, tri.v2}) box.extend(corner);
    return box;
}

/// What a walk of the tree found.
struct TreeWalk {
    std::vector<int> slot_references;  ///< per leaf-order slot: leaves naming it
    int deepest = 0;
};

/// Checks that every child box holds everything below it (with spatial splits a leaf box
/// holds only the clipped part of a triangle: it must then overlap the triangle's box) and
/// the node and leaf limits of `settings`.
void walk_subtree(const ObjectBvh& bvh, NodeRef ref, const BBox3f& box,
                  const EmbreeBvhBuilderSettings& settings, int depth, TreeWalk& walk) {
    ASSERT_LE(depth, kMaxBvhDepth);
    walk.deepest = std::max(walk.deepest, depth);
    if (ref.is_leaf()) {
        ASSERT_LE(ref.prim_count(), settings.max_leaf_size);
        for (std::uint32_t i = ref.first_prim(); i < ref.first_prim() + ref.prim_count(); ++i) {
            ASSERT_LT(i, bvh.prim_ids.size());
            ++walk.slot_references[i];
            const BBox3f tri = triangle_box(bvh.triangles[i]);
            if (has_splits(settings))
                EXPECT_FALSE(intersection(box, tri).is_empty()) << "slot " << i;
            else
                EXPECT_TRUE(box.contains(tri)) << "slot " << i;
        }
        return;
    }
    ASSERT_TRUE(ref.is_inner());
    ASSERT_LT(ref.node_id(), bvh.nodes.size());
    const WideNode& node = bvh.nodes[ref.node_id()];
    const int count = node.child_count();
    EXPECT_GE(count, 2);
    EXPECT_LE(count, int(settings.max_branching_factor));
    for (int i = count; i < kBvhWidth; ++i) EXPECT_TRUE(node.children[i].is_empty());
    for (int i = 0; i < count; ++i) {
        EXPECT_TRUE(box.contains(node.child_bounds(i)));
        walk_subtree(bvh, node.children[i], node.child_bounds(i), settings, depth + 1, walk);
    }
}

/// Full validity check of an Embree-built ObjectBvh of `mesh`: boxes nest, leaf-order slots
/// are each referenced once, triangles are the mesh's corners of prim_ids, and every
/// triangle is reachable exactly once (at least once with spatial splits).
void expect_valid_object_bvh(const ObjectBvh& bvh, const Mesh& mesh,
                             const EmbreeBvhBuilderSettings& settings) {
    ASSERT_EQ(bvh.prim_ids.size(), bvh.triangles.size());
    if (mesh.triangles.empty()) {
        EXPECT_TRUE(bvh.root.is_empty());
        return;
    }
    TreeWalk walk{std::vector<int>(bvh.prim_ids.size(), 0)};
    walk_subtree(bvh, bvh.root, bvh.bounds, settings, 0, walk);
    EXPECT_LE(walk.deepest, int(settings.max_depth));
    std::vector<int> prim_references(mesh.triangles.size(), 0);
    for (std::size_t slot = 0; slot < bvh.prim_ids.size(); ++slot) {
        ASSERT_EQ(walk.slot_references[slot], 1) << "leaf-order slot " << slot;
        ASSERT_LT(bvh.prim_ids[slot], mesh.triangles.size());
        ++prim_references[bvh.prim_ids[slot]];
        const auto corners = mesh.corners(bvh.prim_ids[slot]);
        EXPECT_EQ(bvh.triangles[slot].v0, corners[0]);
        EXPECT_EQ(bvh.triangles[slot].v2, corners[2]);
    }
    for (std::size_t prim = 0; prim < prim_references.size(); ++prim) {
        if (has_splits(settings))
            ASSERT_GE(prim_references[prim], 1) << "triangle " << prim << " unreachable";
        else
            ASSERT_EQ(prim_references[prim], 1) << "triangle " << prim << " not reachable once";
    }
}

std::uint64_t object_bvh_hash(const ObjectBvh& bvh) {
    StructureHash hash;
    hash.add<WideNode>(bvh.nodes);
    hash.add_value(bvh.root);
    hash.add<PrimId>(bvh.prim_ids);
    return hash.value();
}

std::string shared_scene_path(const std::string& file) {
    return std::string(REBRAID_SHARED_SCENES) + "/" + file;
}

TEST(EmbreeBvhBuilder, EveryTriangleReachableOnceAndBoxesNest) {
    const Mesh soup = test::make_triangle_soup(20000, 1);
    const Mesh bunny = load_gltf_scene(shared_scene_path("bunny.glb")).meshes.at(0);
    for (const NamedSettings& named : embree_configurations()) {
        for (const Mesh* mesh : {&soup, &bunny}) {
            SCOPED_TRACE(named.name + " / " + mesh->name);
            const ObjectBvh bvh = glue::build_object_bvh_embree(*mesh, named.settings);
            expect_valid_object_bvh(bvh, *mesh, named.settings);
            EXPECT_GT(bvh.nodes.size(), mesh->triangles.size() / 64);
            EXPECT_GT(bvh.build_ms, 0.0);
        }
    }
}

TEST(EmbreeBvhBuilder, HonoursLeafSizeAndBranchingFactor) {
    const Mesh soup = test::make_triangle_soup(5000, 2);
    for (NamedSettings named : embree_configurations()) {
        SCOPED_TRACE(named.name);
        named.settings.max_branching_factor = 4;
        named.settings.max_leaf_size = 1;
        expect_valid_object_bvh(glue::build_object_bvh_embree(soup, named.settings), soup,
                                named.settings);
        named.settings.max_branching_factor = 2;
        named.settings.max_leaf_size = kMaxLeafSize;
        named.settings.min_leaf_size = 8;
        expect_valid_object_bvh(glue::build_object_bvh_embree(soup, named.settings), soup,
                                named.settings);
    }
}

TEST(EmbreeBvhBuilder, EmptyAndSingleTriangleMeshes) {
    Mesh empty;
    Mesh single;
    single.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    single.triangles = {{0, 1, 2}};
    for (const NamedSettings& named : embree_configurations()) {
        SCOPED_TRACE(named.name);
        EXPECT_TRUE(glue::build_object_bvh_embree(empty, named.settings).root.is_empty());
        const ObjectBvh bvh = glue::build_object_bvh_embree(single, named.settings);
        ASSERT_TRUE(bvh.root.is_leaf());
        EXPECT_EQ(bvh.root.prim_count(), 1u);
        EXPECT_EQ(bvh.bounds, (BBox3f{{0, 0, 0}, {1, 1, 0}}));
        expect_valid_object_bvh(bvh, single, named.settings);
    }
}

TEST(EmbreeBvhBuilder, IdenticalAndDegenerateTrianglesStillSplitIntoSmallLeaves) {
    // No SAH split separates identical triangles: Embree must fall back to index splits.
    Mesh copies;
    copies.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 2, 2}};
    for (int i = 0; i < 1000; ++i) copies.triangles.push_back({0, 1, 2});
    for (int i = 0; i < 300; ++i) copies.triangles.push_back({3, 3, 3});  // points
    for (NamedSettings named : embree_configurations()) {
        SCOPED_TRACE(named.name);
        named.settings.max_leaf_size = 2;
        expect_valid_object_bvh(glue::build_object_bvh_embree(copies, named.settings), copies,
                                named.settings);
    }
}

TEST(EmbreeBvhBuilder, HighQualityWithoutSplitsBuildsTheMediumTree) {
    // rtcBuildBVH only differs at high quality through spatial splits; without a split
    // callback it runs the medium (binned SAH) builder. Documented in the settings.
    const Mesh soup = test::make_triangle_soup(20000, 3);
    EXPECT_EQ(object_bvh_hash(
                  glue::build_object_bvh_embree(soup, {.quality = EmbreeBuildQuality::medium})),
              object_bvh_hash(
                  glue::build_object_bvh_embree(soup, {.quality = EmbreeBuildQuality::high})));
}

TEST(EmbreeBvhBuilder, SpatialSplitsReferenceLongTrianglesSeveralTimes) {
    // Large triangles in a soup overlap much: spatial splits should cut some of them.
    const Mesh soup = test::make_triangle_soup(5000, 4, 0.5f);
    const EmbreeBvhBuilderSettings settings{.quality = EmbreeBuildQuality::high,
                                            .can_split_triangles = true};
    const ObjectBvh split = glue::build_object_bvh_embree(soup, settings);
    expect_valid_object_bvh(split, soup, settings);
    EXPECT_GT(split.prim_ids.size(), soup.triangles.size());
    const ObjectBvh unsplit = glue::build_object_bvh_embree(soup, {});
    std::printf(
        "[ SAH      ] soup of 5000 large triangles: medium %.3f, high+splits %.3f "
        "(%zu references)\n",
        object_bvh_sah(unsplit), object_bvh_sah(split), split.prim_ids.size());
    EXPECT_LT(object_bvh_sah(split), object_bvh_sah(unsplit));
}

TEST(EmbreeBvhBuilder, SameTreeWithOneTwoAndEightThreads) {
    // Large enough for Embree's parallel binning, partitioning and subtree tasks.
    const Mesh soup = test::make_triangle_soup(30000, 9, 0.03f);
    // Lift TBB's default cap (the core count) so the arena of 8 really has 8 threads.
    tbb::global_control allow_eight(tbb::global_control::max_allowed_parallelism, 8);
    glue::EmbreeDevice device;
    for (const NamedSettings& named : embree_configurations()) {
        SCOPED_TRACE(named.name);
        std::vector<std::uint64_t> hashes;
        for (int threads : {1, 2, 8}) {
            tbb::task_arena arena(threads);
            arena.execute([&] {
                hashes.push_back(
                    object_bvh_hash(glue::build_object_bvh_embree(device, soup, named.settings)));
            });
        }
        EXPECT_EQ(hashes[0], hashes[1]);
        EXPECT_EQ(hashes[0], hashes[2]);
    }
}

TEST(EmbreeBvhBuilder, EmbreeErrorsBecomeRebraidErrors) {
    // Two levels of 8-wide nodes with leaves of 1 cannot hold 20,000 triangles: Embree
    // reports "depth limit reached" from inside the build.
    const Mesh soup = test::make_triangle_soup(20000, 5);
    try {
        glue::build_object_bvh_embree(soup, {.max_depth = 2, .max_leaf_size = 1});
        ADD_FAILURE() << "expected rebraid::Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("rtcBuildBVH"), std::string::npos) << e.what();
    }
}

TEST(EmbreeBvhBuilderSettings, RejectsOutOfRangeValues) {
    EXPECT_NO_THROW(EmbreeBvhBuilderSettings{}.validate());
    EXPECT_THROW((EmbreeBvhBuilderSettings{.max_branching_factor = 1}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.max_branching_factor = 9}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.max_depth = 0}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.max_depth = kMaxBvhDepth + 1}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.sah_block_size = 3}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.min_leaf_size = 5}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.max_leaf_size = 17}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.max_leaf_size = 0}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.traversal_cost = -1.0f}.validate()), Error);
    EXPECT_THROW((EmbreeBvhBuilderSettings{.intersection_cost = 0.0f}.validate()), Error);
    EXPECT_THROW(glue::embree_object_bvh_builder({.max_leaf_size = 0}), Error);
    EXPECT_THROW(glue::build_object_bvh_embree(Mesh{}, {.max_leaf_size = 0}), Error);
}

// ---- Two-level structures over Embree-built object BVHs against Embree flat ---------------

/// Builds the two-level structure over object BVHs of the project's builder and of each
/// Embree configuration but plain "high" (the medium tree, see above); checks the Embree ones
/// against Embree's flat scene on 10,000 random rays; prints every two-level SAH (docs/design.md
/// definition) with the object build time. Binned SAH must not be worse than Morton, nor
/// spatial splits worse than none.
void expect_two_level_matches_embree_flat(const Scene& scene, const std::string& scene_name) {
    const glue::EmbreeFlatAccel reference(scene);
    const std::vector<Ray> rays = test::varied_rays(reference, scene.bounds(), 10000, 42);
    const test::AccelAnswers expected = test::trace_all(reference, rays);
    std::vector<NamedSettings> configurations = embree_configurations();
    std::erase_if(configurations, [](const NamedSettings& c) { return c.name == "high"; });

    std::string line = "[ SAH      ] " + scene_name + ":";
    const auto add_to_line = [&](const std::string& name, const AccelStats& stats) {
        char cell[96];
        std::snprintf(cell, sizeof cell, " %s %.3f (%.1f ms)", name.c_str(), stats.sah.value_or(0),
                      stats.build_ms - stats.top_build_ms.value_or(0.0));
        line += cell;
    };
    add_to_line("own", build_two_level_accel(scene, own_object_bvh_builder()).stats());
    std::vector<double> sahs;
    for (const NamedSettings& named : configurations) {
        SCOPED_TRACE(scene_name + " / embree-" + named.name);
        const InstancedAccel accel =
            build_two_level_accel(scene, glue::embree_object_bvh_builder(named.settings));
        test::expect_same_answers(scene, rays, expected, test::trace_all(accel, rays),
                                  test::tolerance_for(scene.bounds()));
        const AccelStats stats = accel.stats();
        ASSERT_TRUE(stats.sah.has_value());
        EXPECT_GE(*stats.sah, 1.0);  // the root is always visited
        sahs.push_back(*stats.sah);
        add_to_line("embree-" + named.name, stats);
    }
    std::printf("%s\n", line.c_str());
    // configurations: low, medium, high+splits
    EXPECT_LE(sahs[1], sahs[0] * 1.02) << "binned SAH worse than Morton";
    EXPECT_LE(sahs[2], sahs[1] * 1.02) << "spatial splits made the SAH worse";
}

TEST(EmbreeObjectBvhs, DefaultSceneTwoLevelMatchesEmbreeFlat) {
    expect_two_level_matches_embree_flat(make_default_scene(), "default scene");
}

TEST(EmbreeObjectBvhs, GeneratedScenesTwoLevelMatchesEmbreeFlat) {
    for (const test::NamedScene& named : test::generated_scenes())
        expect_two_level_matches_embree_flat(named.scene, named.name);
}

class SharedSceneEmbreeObjectBvhs : public testing::TestWithParam<std::string> {};

TEST_P(SharedSceneEmbreeObjectBvhs, TwoLevelMatchesEmbreeFlat) {
    expect_two_level_matches_embree_flat(load_gltf_scene(shared_scene_path(GetParam())),
                                         GetParam());
}

INSTANTIATE_TEST_SUITE_P(SharedScenes, SharedSceneEmbreeObjectBvhs,
                         testing::ValuesIn(test::shared_scene_files()),
                         [](const testing::TestParamInfo<std::string>& info) {
                             return test::test_name_of(info.param);
                         });

}  // namespace
}  // namespace rebraid
