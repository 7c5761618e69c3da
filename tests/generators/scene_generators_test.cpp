// Scene generators (rebraid/generators/scene_generators.h), their extra meshes
// (rebraid/generators/mesh_generators_extra.h), the glTF writer and `rebraid generate`.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/generators/mesh_generators_extra.h"
#include "rebraid/generators/scene_generators.h"
#include "rebraid/generators/world_space_objects.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/io/gltf_writer.h"

namespace rebraid {
namespace {

namespace fs = std::filesystem;

/// `count` placements' worth of objects: world-space Powerplant objects hold
/// kPowerplantPiecesPerObject pieces each (at least 2 objects, so two can overlap).
std::uint32_t scaled_count(SceneKind kind, std::uint32_t count) {
    if (kind != SceneKind::kPowerplant) return count;
    return std::max(2u, count / kPowerplantPiecesPerObject);
}

fs::path scratch_path(const std::string& name) {
    const fs::path dir = fs::path(REBRAID_TEST_TMP) / "scene_generators_test";
    fs::create_directories(dir);
    return dir / name;
}

/// Kinds whose instances are meant to overlap their neighbours.
bool is_overlap_kind(SceneKind kind) {
    return kind != SceneKind::kCity;
}

/// True when the boxes share a region of positive volume (touching is not overlapping).
bool boxes_overlap(const BBox3f& a, const BBox3f& b) {
    for (int axis = 0; axis < 3; ++axis)
        if (!(a.min[axis] < b.max[axis] && b.min[axis] < a.max[axis])) return false;
    return true;
}

struct OverlapSummary {
    double overlapping_fraction = 0;  ///< instances whose box overlaps at least one other
    double mean_overlaps = 0;         ///< other boxes overlapped, per instance
};

OverlapSummary summarize_overlap(const Scene& scene) {
    std::vector<BBox3f> boxes;
    for (InstanceId i = 0; i < scene.instances.size(); ++i)
        boxes.push_back(scene.instance_bounds(i));
    std::vector<int> overlaps(boxes.size(), 0);
    for (std::size_t i = 0; i < boxes.size(); ++i)
        for (std::size_t j = i + 1; j < boxes.size(); ++j)
            if (boxes_overlap(boxes[i], boxes[j])) ++overlaps[i], ++overlaps[j];
    OverlapSummary summary;
    for (int count : overlaps) {
        summary.overlapping_fraction += count > 0 ? 1 : 0;
        summary.mean_overlaps += count;
    }
    summary.overlapping_fraction /= static_cast<double>(boxes.size());
    summary.mean_overlaps /= static_cast<double>(boxes.size());
    return summary;
}

void expect_same_transform(const AffineTransform& a, const AffineTransform& b,
                           const std::string& where) {
    const Vec3f columns_a[4] = {a.col_x, a.col_y, a.col_z, a.translation};
    const Vec3f columns_b[4] = {b.col_x, b.col_y, b.col_z, b.translation};
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 3; ++row) {
            const float x = columns_a[c][row], y = columns_b[c][row];
            EXPECT_LE(std::fabs(x - y), 1e-6f * std::max(1.0f, std::fabs(x)))
                << where << " column " << c << " row " << row;
        }
}

/// Meshes bit for bit; instance count, mesh ids and transforms (tight tolerance).
void expect_same_scene(const Scene& expected, const Scene& actual) {
    ASSERT_EQ(actual.meshes.size(), expected.meshes.size());
    for (std::size_t m = 0; m < expected.meshes.size(); ++m) {
        EXPECT_EQ(actual.meshes[m].name, expected.meshes[m].name) << "mesh " << m;
        EXPECT_TRUE(actual.meshes[m].positions == expected.meshes[m].positions) << "mesh " << m;
        EXPECT_TRUE(actual.meshes[m].triangles == expected.meshes[m].triangles) << "mesh " << m;
    }
    ASSERT_EQ(actual.instances.size(), expected.instances.size());
    for (std::size_t i = 0; i < expected.instances.size(); ++i) {
        EXPECT_EQ(actual.instances[i].mesh_id, expected.instances[i].mesh_id) << "instance " << i;
        expect_same_transform(expected.instances[i].object_to_world,
                              actual.instances[i].object_to_world, "instance " + std::to_string(i));
    }
}

bool same_scene_exactly(const Scene& a, const Scene& b) {
    if (a.meshes.size() != b.meshes.size() || a.instances.size() != b.instances.size())
        return false;
    for (std::size_t m = 0; m < a.meshes.size(); ++m)
        if (a.meshes[m].positions != b.meshes[m].positions ||
            a.meshes[m].triangles != b.meshes[m].triangles)
            return false;
    for (std::size_t i = 0; i < a.instances.size(); ++i)
        if (a.instances[i].mesh_id != b.instances[i].mesh_id ||
            !(a.instances[i].object_to_world == b.instances[i].object_to_world))
            return false;
    return true;
}

/// Six times the signed volume enclosed by the mesh (positive for outward winding).
double signed_volume(const Mesh& mesh) {
    double six_volume = 0;
    for (PrimId t = 0; t < mesh.triangles.size(); ++t) {
        const auto [a, b, c] = mesh.corners(t);
        six_volume += static_cast<double>(dot(a, cross(b, c)));
    }
    return six_volume / 6.0;
}

/// True when every directed edge occurs once and its reverse also occurs: a closed,
/// consistently oriented surface.
bool is_closed_and_oriented(const Mesh& mesh) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
    for (const auto& [edge, count] : edges) {
        const auto reverse = edges.find({edge.second, edge.first});
        if (count != 1 || reverse == edges.end() || reverse->second != 1) return false;
    }
    return true;
}

// ---- Kinds and settings ------------------------------------------------------------------

TEST(SceneKindNames, ParseRoundTripsEveryName) {
    EXPECT_EQ(all_scene_kinds().size(), 5u);
    for (SceneKind kind : all_scene_kinds())
        EXPECT_EQ(parse_scene_kind(scene_kind_name(kind)), kind) << scene_kind_name(kind);
}

TEST(SceneKindNames, UnknownNameErrorListsValidKinds) {
    try {
        parse_scene_kind("forest");
        FAIL() << "no error for an unknown kind";
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find("forest"), std::string::npos) << message;
        for (SceneKind kind : all_scene_kinds())
            EXPECT_NE(message.find(scene_kind_name(kind)), std::string::npos) << message;
    }
}

TEST(SceneGenerators, RejectsTooManyInstances) {
    EXPECT_THROW(generate_scene(SceneKind::kCity, {.instance_count = kMaxGeneratedInstances + 1}),
                 Error);
}

// ---- Generated scenes ----------------------------------------------------------------------

TEST(SceneGenerators, EveryKindIsValidWithExactlyTheRequestedInstances) {
    for (SceneKind kind : all_scene_kinds())
        for (std::uint32_t count : {1u, 2u, 7u, 50u, 333u}) {
            if (kind == SceneKind::kPowerplant && count > 7) count = scaled_count(kind, count);
            const Scene scene = generate_scene(kind, {.instance_count = count, .seed = 5});
            SCOPED_TRACE(std::string(scene_kind_name(kind)) + " " + std::to_string(count));
            EXPECT_NO_THROW(scene.validate());
            EXPECT_EQ(scene.instances.size(), count);
            for (const Mesh& mesh : scene.meshes) EXPECT_FALSE(mesh.triangles.empty());
        }
}

TEST(SceneGenerators, DefaultsHaveTheDocumentedInstanceCounts) {
    for (SceneKind kind : all_scene_kinds()) {
        const Scene scene = generate_scene(kind, {});
        SCOPED_TRACE(scene_kind_name(kind));
        EXPECT_NO_THROW(scene.validate());
        EXPECT_EQ(scene.instances.size(), default_instance_count(kind));
        if (kind == SceneKind::kHuge) continue;  // checked below
        // "Hundreds" to "thousands" of instances (Powerplant: dozens of large objects, as
        // the paper's 56), and few enough triangles for a flat BVH.
        EXPECT_GE(scene.instances.size(), kind == SceneKind::kPowerplant ? 40u : 100u);
        EXPECT_LE(scene.instances.size(), 12'000u);
        EXPECT_GE(scene.instanced_triangle_count(), 500'000u);
        EXPECT_LE(scene.instanced_triangle_count(), 20'000'000u);
    }
    // The forest is the paper's Trees scene at a third of its size.
    EXPECT_GE(default_instance_count(SceneKind::kTrees), 1'000u);
    EXPECT_GE(default_instance_count(SceneKind::kCrown), 100u);
    EXPECT_LT(default_instance_count(SceneKind::kCrown), 1'000u);
}

TEST(SceneGenerators, HugeHasTenThousandInstancesAndHundredMillionTriangles) {
    const Scene scene = generate_scene(SceneKind::kHuge, {});
    EXPECT_GE(scene.instances.size(), 10'000u);
    EXPECT_GE(scene.instanced_triangle_count(), 100'000'000u);
    // Instancing keeps it small: the distinct meshes hold a tiny fraction of the triangles.
    EXPECT_LE(scene.mesh_triangle_count(), 1'000'000u);
    EXPECT_NO_THROW(scene.validate());
}

TEST(SceneGenerators, SameSeedGivesIdenticalSceneOtherSeedAnother) {
    for (SceneKind kind : all_scene_kinds()) {
        SCOPED_TRACE(scene_kind_name(kind));
        const Scene a =
            generate_scene(kind, {.instance_count = scaled_count(kind, 200), .seed = 42});
        const Scene b =
            generate_scene(kind, {.instance_count = scaled_count(kind, 200), .seed = 42});
        const Scene c =
            generate_scene(kind, {.instance_count = scaled_count(kind, 200), .seed = 43});
        EXPECT_TRUE(same_scene_exactly(a, b));
        EXPECT_FALSE(same_scene_exactly(a, c));
    }
}

TEST(SceneGenerators, OverlapKindsOverlapHeavilyCityNot) {
    for (SceneKind kind : all_scene_kinds()) {
        const Scene scene =
            generate_scene(kind, {.instance_count = scaled_count(kind, 500), .seed = 9});
        const OverlapSummary overlap = summarize_overlap(scene);
        SCOPED_TRACE(std::string(scene_kind_name(kind)) + ": overlapping fraction " +
                     std::to_string(overlap.overlapping_fraction) + ", mean overlaps " +
                     std::to_string(overlap.mean_overlaps));
        if (is_overlap_kind(kind)) {
            EXPECT_GE(overlap.overlapping_fraction, 0.9);
            EXPECT_GE(overlap.mean_overlaps, 3.0);
        } else {
            EXPECT_LE(overlap.overlapping_fraction, 0.01);
            EXPECT_LE(overlap.mean_overlaps, 0.01);
        }
    }
}

/// Lowest point of instance `id`'s triangles in world space (its box, the conservative image
/// of the mesh's box, may reach lower when the instance is rotated).
float lowest_point(const Scene& scene, InstanceId id) {
    const Instance& instance = scene.instances[id];
    float lowest = std::numeric_limits<float>::infinity();
    for (const Vec3f& p : scene.meshes[instance.mesh_id].positions)
        lowest = std::min(lowest, instance.object_to_world.transform_point(p).y);
    return lowest;
}

TEST(SceneGenerators, ObjectsRestOnTheGroundYUp) {
    for (SceneKind kind : all_scene_kinds()) {
        const Scene scene =
            generate_scene(kind, {.instance_count = scaled_count(kind, 300), .seed = 2});
        SCOPED_TRACE(scene_kind_name(kind));
        std::vector<float> lowest;
        for (InstanceId i = 0; i < scene.instances.size(); ++i)
            lowest.push_back(lowest_point(scene, i));
        // Nothing below the ground (the rim of a tilted trunk may dip a hair below it) ...
        const float scene_lowest = *std::min_element(lowest.begin(), lowest.end());
        EXPECT_GE(scene_lowest, -0.05f);
        EXPECT_LE(scene_lowest, 0.05f);
        // ... and scenes are taller than a sheet.
        EXPECT_GT(scene.bounds().extent().y, 0.5f);
        // Trees and buildings each stand on the ground.
        if (kind == SceneKind::kTrees || kind == SceneKind::kCity || kind == SceneKind::kHuge) {
            for (InstanceId i = 0; i < scene.instances.size(); ++i)
                EXPECT_LE(lowest[i], 0.05f) << "instance " << i << " floats";
        }
    }
}

// ---- Extra meshes --------------------------------------------------------------------------

TEST(MeshGeneratorsExtra, TriangleCountsMatchTheirFormulas) {
    EXPECT_EQ(make_cylinder({.segment_count = 10, .length_segment_count = 3}).triangles.size(),
              2u * 10 * 3 + 2 * 10);
    EXPECT_EQ(make_cylinder({.segment_count = 10, .is_capped = false}).triangles.size(), 20u);
    EXPECT_EQ(make_branching_tree(
                  {.level_count = 2, .branch_count = 3, .segment_count = 5, .leaf_count = 4})
                  .triangles.size(),
              2u * 5 * (1 + 3 + 9) + 2 * 4 * 9);
    EXPECT_EQ(
        make_conifer({.tier_count = 3, .segment_count = 12, .ring_count = 4}).triangles.size(),
        32u + 3 * 2 * 4 * 12);
    EXPECT_EQ(make_ring_band({.segment_count = 30}).triangles.size(), 8u * 30);
    EXPECT_EQ(make_gem({.facet_count = 9}).triangles.size(), 4u * 9);
    EXPECT_EQ(make_i_beam({.length_segment_count = 1}).triangles.size(), 36u);
    EXPECT_EQ(make_i_beam({.length_segment_count = 5}).triangles.size(), 3u * (8 * 5 + 4));
    EXPECT_EQ(make_flanged_pipe({.segment_count = 8, .length_segment_count = 5, .flange_count = 3})
                  .triangles.size(),
              2u * 8 * 6 + 3 * 4 * 8);
    EXPECT_EQ(make_truss({.panel_count = 7}).triangles.size(), 4u * (8 * 7 + 4) + 12u * 4 * 7);
}

TEST(MeshGeneratorsExtra, ClosedPartsAreWatertightAndWoundOutward) {
    const std::vector<Mesh> closed = {
        make_cylinder({}),
        make_ring_band({.crest_count = 8, .crest_height = 0.1f}),
        make_gem({}),
    };
    for (const Mesh& mesh : closed) {
        EXPECT_TRUE(is_closed_and_oriented(mesh)) << mesh.name;
        EXPECT_GT(signed_volume(mesh), 0.0) << mesh.name;
    }
    // Unions of closed parts: each part is closed and outward, so the sum is positive.
    for (const Mesh& mesh : {make_conifer({}), make_i_beam({}), make_flanged_pipe({}),
                             make_truss({}), make_building({})})
        EXPECT_GT(signed_volume(mesh), 0.0) << mesh.name;
}

TEST(MeshGeneratorsExtra, CylinderEnclosesItsVolume) {
    const Mesh cylinder = make_cylinder({.radius = 0.5f, .height = 2.0f, .segment_count = 256});
    const double expected = 3.14159265358979 * 0.25 * 2.0;
    EXPECT_NEAR(signed_volume(cylinder), expected, 0.005 * expected);
}

TEST(MeshGeneratorsExtra, BuildingFitsItsFootprint) {
    const BuildingSettings settings{.width = 0.7f, .depth = 0.5f, .height = 2.0f, .tier_count = 3};
    const BBox3f box = make_building(settings).bounds();
    EXPECT_GE(box.min.x, -0.35f);
    EXPECT_LE(box.max.x, 0.35f);
    EXPECT_GE(box.min.z, -0.25f);
    EXPECT_LE(box.max.z, 0.25f);
    EXPECT_FLOAT_EQ(box.min.y, 0.0f);
    EXPECT_NEAR(box.max.y, 2.0f * 1.04f, 1e-4f);
}

TEST(MeshGeneratorsExtra, SameSettingsSameMeshOtherSeedAnother) {
    const Mesh a = make_branching_tree({.seed = 3});
    const Mesh b = make_branching_tree({.seed = 3});
    const Mesh c = make_branching_tree({.seed = 4});
    EXPECT_TRUE(a.positions == b.positions);
    EXPECT_FALSE(a.positions == c.positions);
}

// ---- glTF writer ---------------------------------------------------------------------------

TEST(GltfWriter, EveryKindRoundTripsThroughGlbAndGltf) {
    for (SceneKind kind : all_scene_kinds()) {
        const Scene scene =
            generate_scene(kind, {.instance_count = scaled_count(kind, 60), .seed = 8});
        for (const char* extension : {".glb", ".gltf"}) {
            SCOPED_TRACE(std::string(scene_kind_name(kind)) + extension);
            const fs::path path = scratch_path(std::string(scene_kind_name(kind)) + extension);
            write_gltf_scene(scene, path.string());
            expect_same_scene(scene, load_gltf_scene(path.string()));
        }
    }
}

TEST(GltfWriter, LargeMeshUsesThirtyTwoBitIndices) {
    // More than 65,535 vertices: the indices cannot be stored as unsigned short.
    Scene scene;
    scene.meshes.push_back(make_uv_sphere({.segment_count = 400, .ring_count = 200}));
    ASSERT_GT(scene.meshes[0].positions.size(), 65'535u);
    scene.instances.push_back({0, AffineTransform::rotate({0, 0, 1}, 0.3f)});
    scene.instances.push_back(
        {0, AffineTransform::translate({3, -1, 2.5f}) * AffineTransform::scale({1, 2, 0.5f})});
    const fs::path path = scratch_path("large_mesh.glb");
    write_gltf_scene(scene, path.string());
    expect_same_scene(scene, load_gltf_scene(path.string()));
}

TEST(GltfWriter, RejectsWhatGltfCannotHold) {
    Scene scene = generate_scene(SceneKind::kCity, {.instance_count = 3});
    EXPECT_THROW(write_gltf_scene(scene, scratch_path("scene.obj").string()), Error);
    EXPECT_THROW(write_gltf_scene(scene, scratch_path("missing_dir/x/scene.glb").string()), Error);
    Scene no_instances = scene;
    no_instances.instances.clear();
    EXPECT_THROW(write_gltf_scene(no_instances, scratch_path("empty.glb").string()), Error);
    Scene empty_mesh = scene;
    empty_mesh.meshes.push_back({});
    EXPECT_THROW(write_gltf_scene(empty_mesh, scratch_path("empty_mesh.glb").string()), Error);
    Scene bad_mesh_id = scene;
    bad_mesh_id.instances[0].mesh_id = 99;
    EXPECT_THROW(write_gltf_scene(bad_mesh_id, scratch_path("bad.glb").string()), Error);
}

// ---- Command line --------------------------------------------------------------------------

/// Runs the rebraid binary with `arguments` (already shell-safe); returns its exit code and
/// writes its standard output and error to `output`.
int run_rebraid(const std::string& arguments, std::string& output) {
    // One capture file per test: ctest runs the tests of this file in parallel processes.
    const fs::path capture = scratch_path(
        std::string(testing::UnitTest::GetInstance()->current_test_info()->name()) + ".out");
    const std::string command =
        std::string("'") + REBRAID_CLI + "' " + arguments + " >'" + capture.string() + "' 2>&1";
    const int status = std::system(command.c_str());
    std::ifstream in(capture);
    std::ostringstream text;
    text << in.rdbuf();
    output = text.str();
    return (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
}

TEST(GenerateCommand, WritesALoadableSceneEqualToTheGenerator) {
    const fs::path path = scratch_path("cli/city.glb");
    fs::remove(path);
    std::string output;
    ASSERT_EQ(
        run_rebraid("generate city -o '" + path.string() + "' --instances 50 --seed 4", output), 0)
        << output;
    EXPECT_NE(output.find("instances 50"), std::string::npos) << output;
    const Scene loaded = load_gltf_scene(path.string());
    EXPECT_EQ(loaded.instances.size(), 50u);
    // The file lists each mesh's instances together, in generation order (one
    // EXT_mesh_gpu_instancing node per mesh).
    Scene expected = generate_scene(SceneKind::kCity, {.instance_count = 50, .seed = 4});
    std::stable_sort(expected.instances.begin(), expected.instances.end(),
                     [](const Instance& a, const Instance& b) { return a.mesh_id < b.mesh_id; });
    expect_same_scene(expected, loaded);
}

TEST(SceneGenerators, CrownAndPowerplantAreObjectsInWorldSpaceByDefault) {
    for (SceneKind kind : all_scene_kinds()) {
        SCOPED_TRACE(std::string(scene_kind_name(kind)));
        if (kind == SceneKind::kHuge) continue;  // an instanced forest like trees, only larger
        const Scene scene = generate_scene(kind, {.instance_count = 12, .seed = 3});
        if (kind != SceneKind::kCrown && kind != SceneKind::kPowerplant) {
            expect_same_scene(scene, generate_scene(kind, {.placement = ObjectPlacement::instanced,
                                                           .instance_count = 12,
                                                           .seed = 3}));
            continue;
        }
        const std::uint32_t pieces =
            kind == SceneKind::kPowerplant ? kPowerplantPiecesPerObject : 1;
        const Scene instanced = generate_scene(
            kind,
            {.placement = ObjectPlacement::instanced, .instance_count = 12 * pieces, .seed = 3});
        expect_same_scene(scene, bake_instances_into_world_space(instanced, pieces));
        EXPECT_EQ(scene.meshes.size(), 12u);
    }
}

TEST(WorldSpaceObjects, BakesGroupsOfInstancesIntoWorldSpaceMeshes) {
    const Scene scene = generate_scene(SceneKind::kTrees, {.instance_count = 7, .seed = 5});
    const Scene baked = bake_instances_into_world_space(scene, 3);
    ASSERT_EQ(baked.instances.size(), 3u);  // 3 + 3 + 1
    ASSERT_EQ(baked.meshes.size(), 3u);
    EXPECT_EQ(baked.instanced_triangle_count(), scene.instanced_triangle_count());
    EXPECT_NO_THROW(baked.validate());
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(baked.instances[k].mesh_id, MeshId(k));
        EXPECT_EQ(baked.instances[k].object_to_world, AffineTransform::identity());
    }
    // Triangle j of a placed mesh, corner by corner, where the instance put it (within
    // rounding: the library may fuse multiply-adds where this file does not).
    std::size_t first_triangle = 0;        // of the placed mesh within the object
    for (std::size_t i = 3; i < 6; ++i) {  // the second object
        const Instance& placed = scene.instances[i];
        const Mesh& source = scene.meshes[placed.mesh_id];
        for (PrimId j = 0; j < source.triangles.size(); j += 13) {
            const auto expected = source.corners(j);
            const auto actual = baked.meshes[1].corners(PrimId(first_triangle + j));
            for (int c = 0; c < 3; ++c) {
                const Vec3f world = placed.object_to_world.transform_point(expected[c]);
                for (int axis = 0; axis < 3; ++axis)
                    EXPECT_NEAR(actual[c][axis], world[axis],
                                1e-6f * (1.0f + std::fabs(world[axis])));
            }
        }
        first_triangle += source.triangles.size();
    }
    EXPECT_EQ(first_triangle, baked.meshes[1].triangles.size());
    EXPECT_THROW(bake_instances_into_world_space(scene, 0), Error);
}

TEST(GenerateCommand, PlacementOptionChoosesInstancedOrWorldSpace) {
    const fs::path path = scratch_path("cli/crown_instanced.glb");
    std::string output;
    ASSERT_EQ(run_rebraid(
                  "generate crown -o '" + path.string() + "' --instances 30 --placement instanced",
                  output),
              0)
        << output;
    EXPECT_LT(load_gltf_scene(path.string()).meshes.size(), 30u);
    ASSERT_EQ(run_rebraid(
                  "generate city -o '" + path.string() + "' --instances 30 --placement world-space",
                  output),
              0)
        << output;
    EXPECT_EQ(load_gltf_scene(path.string()).meshes.size(), 30u);
    EXPECT_NE(run_rebraid("generate city -o '" + path.string() + "' --placement nowhere", output),
              0);
}

TEST(GenerateCommand, UnknownKindFailsListingTheKinds) {
    std::string output;
    EXPECT_NE(run_rebraid("generate forest -o '" + scratch_path("x.glb").string() + "'", output),
              0);
    EXPECT_NE(output.find("powerplant"), std::string::npos) << output;
}

}  // namespace
}  // namespace rebraid
