#include "rebraid/generators/default_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include "rebraid/generators/mesh_generators.h"

namespace rebraid {
namespace {

constexpr double kPi = std::numbers::pi;

bool boxes_overlap(const BBox3f& a, const BBox3f& b) {
    return !intersection(a, b).is_empty();
}

/// Signed volume enclosed by a closed mesh (divergence theorem); positive when triangles wind
/// counter-clockwise seen from outside.
double signed_volume(const Mesh& mesh) {
    double volume = 0.0;
    for (PrimId t = 0; t < mesh.triangles.size(); ++t) {
        const auto [a, b, c] = mesh.corners(t);
        volume += static_cast<double>(dot(a, cross(b, c))) / 6.0;
    }
    return volume;
}

/// True when every directed edge appears once and its reverse once: a closed, consistently
/// oriented surface with no holes.
bool is_closed_and_consistent(const Mesh& mesh) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed_edges;
    for (const Triangle& t : mesh.triangles)
        for (int e = 0; e < 3; ++e) ++directed_edges[{t[e], t[(e + 1) % 3]}];
    for (const auto& [edge, count] : directed_edges) {
        if (count != 1) return false;
        const auto reverse = directed_edges.find({edge.second, edge.first});
        if (reverse == directed_edges.end() || reverse->second != 1) return false;
    }
    return true;
}

TEST(DefaultScene, ValidatesAndHasSeveralHundredInstances) {
    const Scene scene = make_default_scene();
    EXPECT_NO_THROW(scene.validate());
    EXPECT_GE(scene.instances.size(), 300u);
    EXPECT_LE(scene.instances.size(), 1000u);
    std::size_t detailed_mesh_count = 0;
    for (const Mesh& mesh : scene.meshes)
        detailed_mesh_count += mesh.triangles.size() >= 1000 ? 1 : 0;
    EXPECT_GE(detailed_mesh_count, 3u);
    // Big enough to matter, small enough that a flat BVH over it builds quickly.
    EXPECT_GE(scene.instanced_triangle_count(), 500000u);
    EXPECT_LE(scene.instanced_triangle_count(), 2000000u);
}

TEST(DefaultScene, EveryMeshIsUsedAndSharedMeshesAreReused) {
    const Scene scene = make_default_scene();
    std::vector<std::size_t> uses(scene.meshes.size(), 0);
    for (const Instance& instance : scene.instances) ++uses[instance.mesh_id];
    for (std::size_t m = 0; m < uses.size(); ++m) EXPECT_GE(uses[m], 1u) << "mesh " << m;
    EXPECT_GE(*std::max_element(uses.begin(), uses.end()), 50u);
}

TEST(DefaultScene, TwoCallsGiveIdenticalScenes) {
    const Scene a = make_default_scene();
    const Scene b = make_default_scene();
    ASSERT_EQ(a.meshes.size(), b.meshes.size());
    for (std::size_t m = 0; m < a.meshes.size(); ++m) {
        EXPECT_EQ(a.meshes[m].name, b.meshes[m].name);
        EXPECT_EQ(a.meshes[m].positions, b.meshes[m].positions);
        EXPECT_EQ(a.meshes[m].triangles, b.meshes[m].triangles);
    }
    ASSERT_EQ(a.instances.size(), b.instances.size());
    for (std::size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_EQ(a.instances[i].mesh_id, b.instances[i].mesh_id);
        EXPECT_EQ(a.instances[i].object_to_world, b.instances[i].object_to_world);
    }
}

TEST(DefaultScene, InstanceBoxesOverlapHeavily) {
    const Scene scene = make_default_scene();
    // The ground's box holds everything; leave it out so it cannot inflate the counts.
    const BBox3f scene_box = scene.bounds();
    std::vector<BBox3f> boxes;
    for (InstanceId id = 0; id < scene.instances.size(); ++id) {
        const BBox3f box = scene.instance_bounds(id);
        const Vec3f e = box.extent(), s = scene_box.extent();
        if (e.x > 0.5f * s.x && e.z > 0.5f * s.z) continue;
        boxes.push_back(box);
    }
    ASSERT_GE(boxes.size(), 300u);
    std::vector<std::size_t> neighbour_counts(boxes.size(), 0);
    for (std::size_t i = 0; i < boxes.size(); ++i)
        for (std::size_t j = i + 1; j < boxes.size(); ++j)
            if (boxes_overlap(boxes[i], boxes[j])) {
                ++neighbour_counts[i];
                ++neighbour_counts[j];
            }
    const auto isolated_count =
        std::count(neighbour_counts.begin(), neighbour_counts.end(), std::size_t{0});
    std::size_t neighbour_total = 0;
    for (std::size_t n : neighbour_counts) neighbour_total += n;
    const double mean_neighbours = static_cast<double>(neighbour_total) / boxes.size();
    // Nearly every object touches another's box, and on average several of them: the
    // situation where instance boxes are poor top-level bounds.
    EXPECT_LE(static_cast<double>(isolated_count), 0.05 * boxes.size());
    EXPECT_GE(mean_neighbours, 4.0);
}

TEST(DefaultScene, ObjectsStandOnTheGround) {
    const Scene scene = make_default_scene();
    const BBox3f bounds = scene.bounds();
    // Y is up: the scene is wide and flat, nothing reaches far below the ground.
    EXPECT_GT(bounds.extent().x, 2.0f * bounds.extent().y);
    EXPECT_GT(bounds.extent().z, 2.0f * bounds.extent().y);
    EXPECT_GT(bounds.min.y, -1.0f);
    std::size_t resting_count = 0;
    for (InstanceId id = 0; id < scene.instances.size(); ++id)
        resting_count += std::fabs(scene.instance_bounds(id).min.y) < 0.2f ? 1 : 0;
    EXPECT_GE(static_cast<double>(resting_count), 0.4 * scene.instances.size());
}

TEST(MeshGenerators, ClosedMeshesAreWatertightAndWoundOutward) {
    const std::vector<Mesh> meshes = {make_uv_sphere({}), make_torus({}), make_box({1, 2, 3}),
                                      make_torus_knot({})};
    for (const Mesh& mesh : meshes) {
        EXPECT_TRUE(is_closed_and_consistent(mesh)) << mesh.name;
        EXPECT_GT(signed_volume(mesh), 0.0) << mesh.name;
    }
}

TEST(MeshGenerators, VolumesMatchTheIdealShapes) {
    EXPECT_NEAR(signed_volume(make_box({1, 2, 3})), 48.0, 1e-4);
    const double sphere = signed_volume(make_uv_sphere({.radius = 2.0f}));
    EXPECT_NEAR(sphere / (4.0 / 3.0 * kPi * 8.0), 1.0, 0.02);
    const double torus = signed_volume(make_torus({.major_radius = 1.0f, .minor_radius = 0.25f}));
    EXPECT_NEAR(torus / (2.0 * kPi * kPi * 1.0 * 0.25 * 0.25), 1.0, 0.02);
}

TEST(MeshGenerators, TriangleCountsFollowTheSettings) {
    EXPECT_EQ(make_uv_sphere({.segment_count = 10, .ring_count = 6}).triangles.size(), 2u * 10 * 5);
    EXPECT_EQ(make_torus({.major_segment_count = 20, .minor_segment_count = 7}).triangles.size(),
              2u * 20 * 7);
    EXPECT_EQ(make_torus_knot({.path_segment_count = 50, .tube_segment_count = 5}).triangles.size(),
              2u * 50 * 5);
    EXPECT_EQ(make_helix({.path_segment_count = 30, .tube_segment_count = 6}).triangles.size(),
              2u * 30 * 6);
    EXPECT_EQ(make_ground_grid({.cell_count = 9}).triangles.size(), 2u * 9 * 9);
    // Settings below their minimum are clamped, never a broken mesh.
    EXPECT_EQ(make_uv_sphere({.segment_count = 0, .ring_count = 0}).triangles.size(), 2u * 3 * 1);
}

TEST(MeshGenerators, GroundFacesUpAndStaysBelowZero) {
    const Mesh ground = make_ground_grid({.size = 10.0f, .cell_count = 16, .dip_depth = 0.3f});
    for (const Vec3f& p : ground.positions) {
        EXPECT_LE(p.y, 0.0f);
        EXPECT_GE(p.y, -0.3f - 1e-6f);
    }
    for (PrimId t = 0; t < ground.triangles.size(); ++t) {
        const auto [a, b, c] = ground.corners(t);
        EXPECT_GT(cross(b - a, c - a).y, 0.0f) << "triangle " << t;
    }
    const BBox3f box = ground.bounds();
    EXPECT_FLOAT_EQ(box.min.x, -5.0f);
    EXPECT_FLOAT_EQ(box.max.z, 5.0f);
}

TEST(MeshGenerators, TreeStandsOnOriginAndSeedChangesCanopy) {
    const Mesh tree = make_tree({});
    const BBox3f box = tree.bounds();
    EXPECT_NEAR(box.min.y, 0.0f, 1e-6f);
    EXPECT_GT(box.max.y, 2.0f);
    EXPECT_GT(signed_volume(tree), 0.0);
    EXPECT_GE(tree.triangles.size(), 1000u);
    EXPECT_NE(make_tree({.seed = 1}).positions, make_tree({.seed = 2}).positions);
}

TEST(MeshGenerators, HelixRisesFromZeroToItsHeight) {
    const Mesh helix = make_helix({.coil_radius = 0.5f, .height = 4.0f, .tube_radius = 0.1f});
    const BBox3f box = helix.bounds();
    EXPECT_NEAR(box.max.y - box.min.y, 4.0f, 0.25f);
    EXPECT_NEAR(box.max.x, 0.6f, 0.01f);
    EXPECT_NEAR(box.min.z, -0.6f, 0.01f);
}

}  // namespace
}  // namespace rebraid
