// Traversal of the project's structures (the SIMD kernels compiled into the core library):
// closed meshes stay closed for rays through vertices and edges, every leaf size gives the
// hits a brute-force loop over all triangles gives, occlusion respects the segment, and a
// traversal may start at any node of an object BVH.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "rebraid/bvh/object_traversal.h"
#include "rebraid/core/triangle.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/hit_comparison.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

/// The reference: every world-space triangle tested with the scalar test, closest kept.
class BruteForceAccel final : public Accel {
public:
    explicit BruteForceAccel(const Scene& scene) {
        for (std::size_t i = 0; i < scene.instances.size(); ++i) {
            const Instance& instance = scene.instances[i];
            const Mesh& mesh = scene.meshes[instance.mesh_id];
            for (PrimId p = 0; p < mesh.triangles.size(); ++p) {
                const auto c = mesh.corners(p);
                const AffineTransform& m = instance.object_to_world;
                triangles_.push_back(
                    {m.transform_point(c[0]), m.transform_point(c[1]), m.transform_point(c[2])});
                ids_.push_back({InstanceId(i), p});
            }
        }
    }
    Hit intersect_counted(const Ray& ray, TraversalCounters*) const override {
        Hit hit;
        float tfar = ray.tfar;
        for (std::size_t i = 0; i < triangles_.size(); ++i) {
            float t, u, v;
            if (intersect_triangle(triangles_[i], ray.org, ray.dir, ray.tnear, tfar, t, u, v)) {
                tfar = t;
                hit = {t, ids_[i].first, ids_[i].second, u, v};
            }
        }
        return hit;
    }
    bool occluded(const Ray& ray) const override { return intersect(ray).is_hit(); }
    AccelStats stats() const override { return {}; }

private:
    std::vector<TriangleVerts> triangles_;
    std::vector<std::pair<InstanceId, PrimId>> ids_;
};

/// A UV sphere and a torus, each instanced twice with rotation, non-uniform scale and a
/// mirror.
Scene make_closed_mesh_scene() {
    Scene scene;
    scene.meshes.push_back(make_uv_sphere({.radius = 1.0f, .segment_count = 24, .ring_count = 12}));
    scene.meshes.push_back(make_torus({.major_segment_count = 24, .minor_segment_count = 10}));
    Random random(9);
    for (std::uint32_t i = 0; i < 4; ++i)
        scene.instances.push_back({MeshId(i % 2), test::random_transform(random, 5.0f, true)});
    return scene;
}

/// The flat and two-level structures of `scene`, tracing with `triangle_test`.
std::vector<std::pair<std::string, std::unique_ptr<Accel>>> project_accels(
    const Scene& scene, const BuildSettings& settings = {},
    TriangleTest triangle_test = TriangleTest::moller) {
    std::vector<std::pair<std::string, std::unique_ptr<Accel>>> accels;
    auto flat = std::make_unique<FlatAccel>(scene, settings);
    flat->set_triangle_test(triangle_test);
    accels.emplace_back("flat", std::move(flat));
    auto two_level = std::make_unique<InstancedAccel>(
        build_two_level_accel(scene, own_object_bvh_builder(settings)));
    two_level->set_triangle_test(triangle_test);
    accels.emplace_back("twolevel", std::move(two_level));
    return accels;
}

TEST(Traversal, AxisParallelRaysAlongSharedEdgesOfAGridHit) {
    // A floor of unit squares (two triangles each) and rays straight down through its grid
    // lines and corners: each ray lies in the planes of the boxes of the squares it touches,
    // with zero direction components there, so a box test computing (plane - origin) / 0
    // gets 0 / 0 and loses the squares on both sides (a crack). Every ray must hit, at t 2.
    Mesh floor;
    constexpr int kSquares = 6;
    for (int y = 0; y <= kSquares; ++y)
        for (int x = 0; x <= kSquares; ++x) floor.positions.push_back({float(x), 0.0f, float(y)});
    const auto corner = [](int x, int y) { return std::uint32_t(y * (kSquares + 1) + x); };
    for (int y = 0; y < kSquares; ++y)
        for (int x = 0; x < kSquares; ++x) {
            floor.triangles.push_back({corner(x, y), corner(x + 1, y), corner(x + 1, y + 1)});
            floor.triangles.push_back({corner(x, y), corner(x + 1, y + 1), corner(x, y + 1)});
        }
    Scene scene;
    scene.meshes.push_back(floor);
    scene.instances.push_back({0, AffineTransform::identity()});
    scene.instances.push_back({0, AffineTransform::translate({0.0f, -1.0f, 0.0f})});
    std::vector<Ray> rays;
    for (int y = 1; y < 2 * kSquares; ++y)
        for (int x = 1; x < 2 * kSquares; ++x)
            if (x % 2 == 0 || y % 2 == 0)  // on a grid line (both even: on a corner)
                rays.push_back(
                    {{0.5f * float(x), 2.0f, 0.5f * float(y)}, 0.0f, {0.0f, -1.0f, 0.0f}});
    for (const auto& [name, accel] : project_accels(scene)) {
        SCOPED_TRACE(name);
        std::size_t misses = 0;
        for (const Ray& ray : rays) {
            const Hit hit = accel->intersect(ray);
            misses +=
                !hit.is_hit() || hit.t != 2.0f || hit.instance_id != 0 || !accel->occluded(ray);
        }
        EXPECT_EQ(misses, 0u) << "of " << rays.size() << " rays along grid lines";
    }
}

TEST(Traversal, ClosedMeshesHaveNoHolesAtVerticesAndEdges) {
    // From inside the sphere, every ray leaves through the surface: aiming at the vertices
    // and edge midpoints (where a non-watertight test leaks) must still hit, at t ~ 1. The
    // watertight triangle test promises it; the Möller test (TriangleTest::moller) does not,
    // as Embree's default mode does not.
    Scene scene = make_closed_mesh_scene();
    scene.instances.resize(1);
    scene.instances[0].mesh_id = 0;
    const Mesh& sphere = scene.meshes[0];
    const AffineTransform& to_world = scene.instances[0].object_to_world;
    const Vec3f center = to_world.transform_point({0, 0, 0});
    std::vector<Vec3f> targets;
    for (const Triangle& tri : sphere.triangles) {
        for (int c = 0; c < 3; ++c) {
            const Vec3f a = to_world.transform_point(sphere.positions[tri[c]]);
            const Vec3f b = to_world.transform_point(sphere.positions[tri[(c + 1) % 3]]);
            targets.push_back(a);
            targets.push_back((a + b) * 0.5f);
        }
    }
    for (const auto& [name, accel] : project_accels(scene, {}, TriangleTest::watertight)) {
        SCOPED_TRACE(name);
        std::size_t holes = 0;
        for (const Vec3f& target : targets) {
            const Hit hit = accel->intersect({center, 0.0f, target - center, 1e30f});
            if (!hit.is_hit()) {
                ++holes;
                continue;
            }
            // Chords cut the sphere a little inside its vertices: t is at most 1.
            EXPECT_GT(hit.t, 0.9f);
            EXPECT_LT(hit.t, 1.0f + 1e-4f);
            // The ray through an edge midpoint from far outside (2000 radii away), going
            // inward, must hit the sphere too: shared edges stay closed for far origins.
            // (Vertices are closed by a tolerance of one float epsilon, which covers the
            // rounding of nearby origins only.)
            const bool is_vertex = (&target - targets.data()) % 2 == 0;
            if (is_vertex) continue;
            const Vec3f far_org = center + (target - center) * 2e3f;
            EXPECT_TRUE(accel->intersect({far_org, 0.0f, center - far_org, 1e30f}).is_hit());
        }
        EXPECT_EQ(holes, 0u) << "rays from inside left the closed sphere";
    }
}

TEST(Traversal, EveryLeafSizeMatchesBruteForce) {
    // Leaves of 1 to 16 triangles exercise full and partial groups of the SIMD leaf test.
    Scene scene = test::make_degenerate_scene();
    scene.meshes.push_back(test::make_triangle_soup(300, 21, 0.05f));
    scene.instances.push_back({MeshId(2), AffineTransform::scale({2.0f, 1.0f, 1.5f})});
    const BruteForceAccel reference(scene);
    const std::vector<Ray> rays = test::varied_rays(reference, scene.bounds(), 3000, 5);
    const test::AccelAnswers expected = test::trace_all(reference, rays);
    for (std::uint32_t leaf_size : {1u, 2u, 3u, 4u, 5u, 7u, 8u, 9u, 12u, 16u}) {
        for (const auto& [name, accel] :
             project_accels(scene, {.max_leaf_size = leaf_size, .intersection_cost = 0.2f})) {
            SCOPED_TRACE(name + " with leaves of up to " + std::to_string(leaf_size));
            test::expect_same_answers(scene, rays, expected, test::trace_all(*accel, rays),
                                      test::tolerance_for(scene.bounds()));
        }
    }
}

TEST(Traversal, OcclusionRespectsTheSegment) {
    const Scene scene = make_closed_mesh_scene();
    const std::vector<Ray> rays = generate_random_rays(scene.bounds(), 4000, 8);
    // Random rays through a sparse scene: a few percent hit.
    for (const auto& [name, accel] : project_accels(scene)) {
        SCOPED_TRACE(name);
        std::size_t hits = 0, wrong = 0;
        for (const Ray& ray : rays) {
            const Hit hit = accel->intersect(ray);
            if (accel->occluded(ray) != hit.is_hit()) ++wrong;
            if (!hit.is_hit()) continue;
            ++hits;
            // Nothing is nearer than the closest hit; the segment up to it is occluded.
            Ray shorter = ray, longer = ray;
            shorter.tfar = hit.t * (1.0f - 1e-4f);
            longer.tfar = hit.t * (1.0f + 1e-4f);
            if (accel->occluded(shorter) || !accel->occluded(longer)) ++wrong;
            Ray beyond = ray;
            beyond.tnear = hit.t * (1.0f + 1e-4f);
            const Hit next = accel->intersect(beyond);
            if (next.is_hit() && next.t < beyond.tnear) ++wrong;
        }
        EXPECT_GT(hits, rays.size() / 50);
        EXPECT_EQ(wrong, 0u);
    }
}

/// Triangles below `ref`, in leaf order positions.
void collect_leaf_positions(const ObjectBvh& bvh, NodeRef ref, std::vector<std::uint32_t>& out) {
    if (ref.is_empty()) return;
    if (ref.is_leaf()) {
        for (std::uint32_t i = 0; i < ref.prim_count(); ++i) out.push_back(ref.first_prim() + i);
        return;
    }
    for (NodeRef child : bvh.nodes[ref.node_id()].children) collect_leaf_positions(bvh, child, out);
}

TEST(Traversal, StartsAtAnyNodeOfAnObjectBvh) {
    const Mesh mesh = test::make_triangle_soup(2000, 4, 0.1f);
    const ObjectBvh bvh = build_object_bvh(mesh);
    const std::vector<Ray> rays = generate_random_rays(mesh.bounds(), 300, 6);
    // Every node reference in the tree (inner and leaf) as a start.
    std::vector<NodeRef> starts = {bvh.root};
    for (const WideNode& node : bvh.nodes)
        for (NodeRef child : node.children)
            if (!child.is_empty()) starts.push_back(child);
    std::size_t compared_hits = 0;
    for (std::size_t s = 0; s < starts.size(); s += 7) {
        std::vector<std::uint32_t> below;
        collect_leaf_positions(bvh, starts[s], below);
        for (const Ray& ray : rays) {
            float best_t = ray.tfar;
            bool expect_hit = false;
            for (std::uint32_t i : below) {
                float t, u, v;
                if (intersect_triangle(bvh.triangles[i], ray.org, ray.dir, ray.tnear, best_t, t, u,
                                       v)) {
                    best_t = t;
                    expect_hit = true;
                }
            }
            PreparedRay traversal_ray(ray.org, ray.dir, ray.tnear, ray.tfar);
            Hit hit;
            const bool found = intersect_object_bvh<TriangleTest::watertight>(
                bvh, starts[s], traversal_ray, hit, nullptr);
            ASSERT_EQ(found, expect_hit) << "start " << s;
            PreparedRay occlusion_ray(ray.org, ray.dir, ray.tnear, ray.tfar);
            EXPECT_EQ(occluded_object_bvh<TriangleTest::watertight>(bvh, starts[s], occlusion_ray,
                                                                    nullptr),
                      expect_hit);
            if (!found) continue;
            ++compared_hits;
            EXPECT_FLOAT_EQ(hit.t, best_t);
            // The hit is one of the triangles below the start.
            const auto is_below = [&](std::uint32_t i) { return bvh.prim_ids[i] == hit.prim_id; };
            EXPECT_TRUE(std::any_of(below.begin(), below.end(), is_below));
        }
    }
    EXPECT_GT(compared_hits, 100u);
}

}  // namespace
}  // namespace rebraid
