#include "embree_glue/reference/embree_reference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "embree_glue/reference/embree_device.h"
#include "embree_glue/reference/embree_scene_handle.h"
#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/io/gltf_scene.h"
#include "support/hit_point.h"

namespace rebraid::glue {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// ---- small scenes ------------------------------------------------------------------------

/// Triangle 0 spans (0,0,0), (1,0,0), (0,1,0) in the z = 0 plane; triangle 1 is a larger one
/// in the z = -1 plane, hidden behind it for rays coming from +z.
Mesh two_layer_mesh() {
    Mesh mesh;
    mesh.name = "two_layers";
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, -1, -1}, {3, -1, -1}, {-1, 3, -1}};
    mesh.triangles = {{0, 1, 2}, {3, 4, 5}};
    return mesh;
}

Scene scene_of(std::vector<Mesh> meshes, std::vector<Instance> instances) {
    Scene scene;
    scene.meshes = std::move(meshes);
    scene.instances = std::move(instances);
    return scene;
}

Ray make_ray(Vec3f org, Vec3f dir, float tnear = 0.0f, float tfar = kInf) {
    Ray ray;
    ray.org = org;
    ray.dir = dir;
    ray.tnear = tnear;
    ray.tfar = tfar;
    return ray;
}

/// A height field over [-1, 1]^2 (n x n quads), so rays meet it from both sides.
Mesh wavy_grid(std::uint32_t n) {
    Mesh mesh;
    mesh.name = "wavy_grid";
    for (std::uint32_t j = 0; j <= n; ++j)
        for (std::uint32_t i = 0; i <= n; ++i) {
            const float x = -1.0f + 2.0f * static_cast<float>(i) / static_cast<float>(n);
            const float z = -1.0f + 2.0f * static_cast<float>(j) / static_cast<float>(n);
            mesh.positions.push_back({x, 0.2f * std::sin(3.0f * x) * std::cos(2.0f * z), z});
        }
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            mesh.triangles.push_back({a, b, d});
            mesh.triangles.push_back({a, d, c});
        }
    return mesh;
}

/// A closed unit cube (12 triangles sharing edges) around the origin.
Mesh cube() {
    Mesh mesh;
    mesh.name = "cube";
    for (int c = 0; c < 8; ++c)
        mesh.positions.push_back(
            {(c & 1) ? 0.5f : -0.5f, (c & 2) ? 0.5f : -0.5f, (c & 4) ? 0.5f : -0.5f});
    const std::uint32_t quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
    for (const auto& q : quads) {
        mesh.triangles.push_back({q[0], q[1], q[2]});
        mesh.triangles.push_back({q[0], q[2], q[3]});
    }
    return mesh;
}

/// Overlapping instances of a grid and a cube with random rotations, non-uniform scales and
/// translations; every third instance is mirrored (negative determinant).
Scene mirrored_instances_scene() {
    Scene scene = scene_of({wavy_grid(12), cube()}, {});
    Random random(20240917);
    for (std::uint32_t i = 0; i < 48; ++i) {
        const Vec3f axis{random.next_float(-1, 1), random.next_float(-1, 1), 1.0f};
        Vec3f scale{random.next_float(0.5f, 2.0f), random.next_float(0.5f, 2.0f),
                    random.next_float(0.5f, 2.0f)};
        if (i % 3 == 0) scale.x = -scale.x;
        const Vec3f offset{random.next_float(-3, 3), random.next_float(-3, 3),
                           random.next_float(-3, 3)};
        scene.instances.push_back(
            {i % 2, AffineTransform::translate(offset) *
                        AffineTransform::rotate(axis, random.next_float(0.0f, 6.28f)) *
                        AffineTransform::scale(scale)});
    }
    return scene;
}

// ---- oracles and comparison ---------------------------------------------------------------

/// Closest hit by testing every triangle in double precision (Moeller-Trumbore): an oracle
/// that shares no code with Embree. Small scenes only.
class BruteForceAccel final : public Accel {
public:
    explicit BruteForceAccel(const Scene& scene) {
        for (std::size_t i = 0; i < scene.instances.size(); ++i) {
            const Instance& instance = scene.instances[i];
            const Mesh& mesh = scene.meshes[instance.mesh_id];
            for (PrimId p = 0; p < mesh.triangles.size(); ++p) {
                WorldTriangle triangle{static_cast<InstanceId>(i), p, {}};
                const auto corners = mesh.corners(p);
                for (int c = 0; c < 3; ++c)
                    triangle.corners[c] =
                        to_double(instance.object_to_world.transform_point(corners[c]));
                triangles_.push_back(triangle);
            }
        }
    }

    Hit intersect_counted(const Ray& ray, TraversalCounters* /*counters*/) const override {
        const Double3 org = to_double(ray.org), dir = to_double(ray.dir);
        Hit best;
        double best_t = std::numeric_limits<double>::infinity();
        for (const WorldTriangle& triangle : triangles_) {
            const Double3 e1 = sub(triangle.corners[1], triangle.corners[0]);
            const Double3 e2 = sub(triangle.corners[2], triangle.corners[0]);
            const Double3 p = cross(dir, e2);
            const double det = dot(e1, p);
            if (det == 0.0) continue;
            const Double3 s = sub(org, triangle.corners[0]);
            const double u = dot(s, p) / det;
            const Double3 q = cross(s, e1);
            const double v = dot(dir, q) / det;
            const double t = dot(e2, q) / det;
            if (u < 0.0 || v < 0.0 || u + v > 1.0 || t < ray.tnear || t > ray.tfar || t >= best_t)
                continue;
            best_t = t;
            best = {static_cast<float>(t), triangle.instance_id, triangle.prim_id,
                    static_cast<float>(u), static_cast<float>(v)};
        }
        return best;
    }
    bool occluded(const Ray& ray) const override { return intersect(ray).is_hit(); }
    AccelStats stats() const override { return {}; }

private:
    using Double3 = std::array<double, 3>;
    struct WorldTriangle {
        InstanceId instance_id;
        PrimId prim_id;
        std::array<Double3, 3> corners;
    };
    static Double3 to_double(Vec3f a) { return {a.x, a.y, a.z}; }
    static Double3 sub(const Double3& a, const Double3& b) {
        return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    }
    static double dot(const Double3& a, const Double3& b) {
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    }
    static Double3 cross(const Double3& a, const Double3& b) {
        return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    }
    std::vector<WorldTriangle> triangles_;
};

using test::hit_point_error;

/// How two structures' answers on a batch of rays relate.
struct Agreement {
    std::size_t ray_count = 0;
    std::size_t hit_count = 0;       ///< rays both structures hit
    std::size_t tie_count = 0;       ///< same t (within tolerance), different ids
    std::size_t mismatch_count = 0;  ///< anything else that differs
};

/// Compares closest hits and occlusion (on the full ray, on the segment ending halfway to the
/// hit, and on one reaching just past it), and checks that every hit's ids and barycentrics
/// name the point at its t. t must agree within 1e-4 relative, plus 1e-6 of the scene's
/// diagonal for hits right at the origin (mapping a ray into object space rounds at the
/// scale of the scene's coordinates, not of t).
Agreement compare_accels(const Scene& scene, const Accel& a, const Accel& b,
                         std::span<const Ray> rays) {
    const float diagonal = length(scene.bounds().extent());
    const float t_floor = 1e-6f * diagonal, point_tolerance = 1e-5f * diagonal;
    Agreement result;
    auto fail = [&](std::size_t index, const std::string& what) {
        if (++result.mismatch_count <= 5) ADD_FAILURE() << "ray " << index << ": " << what;
    };
    for (std::size_t r = 0; r < rays.size(); ++r) {
        const Ray& ray = rays[r];
        ++result.ray_count;
        const Hit ha = a.intersect(ray), hb = b.intersect(ray);
        if (a.occluded(ray) != ha.is_hit() || b.occluded(ray) != hb.is_hit())
            fail(r, "occluded() disagrees with intersect() on the full ray");
        if (ha.is_hit() != hb.is_hit()) {
            fail(r, "hit in one structure only (t " + std::to_string(ha.t) + " vs " +
                        std::to_string(hb.t) + ")");
            continue;
        }
        if (!ha.is_hit()) continue;
        ++result.hit_count;
        if (hit_point_error(scene, ray, ha) > point_tolerance ||
            hit_point_error(scene, ray, hb) > point_tolerance)
            fail(r, "a hit's ids and barycentrics do not name the point at its t");
        if (std::fabs(ha.t - hb.t) > 1e-4f * std::max(ha.t, hb.t) + t_floor) {
            fail(r, "t " + std::to_string(ha.t) + " vs " + std::to_string(hb.t));
            continue;
        }
        if (ha.instance_id != hb.instance_id || ha.prim_id != hb.prim_id) ++result.tie_count;

        Ray before = ray, past = ray;
        before.tfar = 0.5f * std::min(ha.t, hb.t);
        past.tfar = 1.001f * std::max(ha.t, hb.t) + t_floor;
        if (a.occluded(before) || b.occluded(before))
            fail(r, "occluded on the segment ending before the closest hit");
        if (!a.occluded(past) || !b.occluded(past))
            fail(r, "not occluded on the segment reaching past the closest hit");
    }
    return result;
}

/// Asserts no mismatches, ties (equal t, different ids) at most `max_tie_fraction` of the
/// rays, and at least 1 % hits so the comparison means something.
void expect_agreement(const Agreement& agreement, double max_tie_fraction) {
    EXPECT_EQ(agreement.mismatch_count, 0u);
    EXPECT_LE(static_cast<double>(agreement.tie_count),
              max_tie_fraction * static_cast<double>(agreement.ray_count))
        << agreement.tie_count << " ties";
    EXPECT_GE(agreement.hit_count * 100, agreement.ray_count) << "fewer than 1 % of rays hit";
    ::testing::Test::RecordProperty("ties", static_cast<int>(agreement.tie_count));
    ::testing::Test::RecordProperty("hits", static_cast<int>(agreement.hit_count));
}

/// Builds both Embree references over `scene` and compares them on 10,000 random rays.
void expect_flat_and_instanced_agree(const Scene& scene, std::uint64_t seed,
                                     double max_tie_fraction) {
    const EmbreeFlatAccel flat(scene);
    const EmbreeInstancedAccel instanced(scene);
    const std::vector<Ray> rays = generate_random_rays(scene.bounds(), 10000, seed);
    expect_agreement(compare_accels(scene, flat, instanced, rays), max_tie_fraction);
}

/// Ties come from rays through shared edges (rare) and from coplanar overlapping triangles,
/// which procedural scenes avoid but real models have (fzk_haus: walls and slabs meeting in
/// one plane give about 0.4 % ties on random rays).
constexpr double kMaxTieFractionProcedural = 0.001;
constexpr double kMaxTieFractionRealModels = 0.01;

// ---- device and scene handle -------------------------------------------------------------

TEST(EmbreeDevice, ThrowIfErrorReportsRecordedErrorOnce) {
    EmbreeDevice device;
    EXPECT_EQ(rtcNewGeometry(device.get(), static_cast<RTCGeometryType>(999)), nullptr);
    // Embree also keeps the code per thread: an independent record of what was reported.
    const std::string expected_prefix = std::string("rtcNewGeometry: Embree error ") +
                                        embree_error_name(rtcGetDeviceError(device.get())) + ": ";
    try {
        device.throw_if_error("rtcNewGeometry");
        FAIL() << "no error was recorded";
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_EQ(message.rfind(expected_prefix, 0), 0u) << message;
        EXPECT_GT(message.size(), expected_prefix.size()) << "Embree's message is missing";
    }
    EXPECT_NO_THROW(device.throw_if_error("nothing failed since"));
}

TEST(EmbreeDevice, KeepsRecordingErrorsAfterMove) {
    EmbreeDevice first;
    EmbreeDevice second(std::move(first));
    EXPECT_EQ(first.get(), nullptr);
    EmbreeDevice third("threads=1");
    third = std::move(second);
    rtcNewGeometry(third.get(), static_cast<RTCGeometryType>(999));
    EXPECT_THROW(third.throw_if_error("rtcNewGeometry"), Error);
    EXPECT_NO_THROW(first.throw_if_error("moved-from device"));
}

TEST(EmbreeDevice, UnparsableConfigIsAClearError) {
    try {
        EmbreeDevice device("threads=not_a_number");
        FAIL() << "Embree accepted the config";
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find("rtcNewDevice"), std::string::npos) << message;
        EXPECT_NE(message.find("threads=not_a_number"), std::string::npos) << message;
    }
}

TEST(EmbreeSceneHandle, ReleasesSceneAndItsMemory) {
    EmbreeDevice device;
    const std::int64_t before = device.allocated_bytes();
    {
        EmbreeSceneHandle scene(device);
        ASSERT_NE(scene.get(), nullptr);
        EmbreeSceneHandle moved = std::move(scene);
        EXPECT_EQ(scene.get(), nullptr);
        rtcCommitScene(moved.get());
        EXPECT_NO_THROW(device.throw_if_error("rtcCommitScene"));
    }
    EXPECT_EQ(device.allocated_bytes(), before);
}

// ---- hand-made scenes, both structures ---------------------------------------------------

template <class AccelType>
class EmbreeReferenceTest : public ::testing::Test {};
using EmbreeReferenceTypes = ::testing::Types<EmbreeFlatAccel, EmbreeInstancedAccel>;
TYPED_TEST_SUITE(EmbreeReferenceTest, EmbreeReferenceTypes);

TYPED_TEST(EmbreeReferenceTest, HitsTriangleAtHandComputedT) {
    const TypeParam accel(scene_of({two_layer_mesh()}, {{0, AffineTransform::identity()}}));
    // From z = 3 with dir.z = -2 the plane z = 0 is reached at t = 1.5, at (0.25, 0.5, 0):
    // barycentric weights 0.25 on vertex 1 and 0.5 on vertex 2.
    const Hit front = accel.intersect(make_ray({0.25f, 0.5f, 3.0f}, {0, 0, -2}));
    EXPECT_NEAR(front.t, 1.5f, 1e-6f);
    EXPECT_EQ(front.instance_id, 0u);
    EXPECT_EQ(front.prim_id, 0u);
    EXPECT_NEAR(front.u, 0.25f, 1e-6f);
    EXPECT_NEAR(front.v, 0.5f, 1e-6f);
    // From below, the z = -1 triangle comes first: t = (-1 - -4) / 1 = 3.
    const Hit back = accel.intersect(make_ray({0.25f, 0.5f, -4.0f}, {0, 0, 1}));
    EXPECT_NEAR(back.t, 3.0f, 1e-6f);
    EXPECT_EQ(back.prim_id, 1u);
}

TYPED_TEST(EmbreeReferenceTest, MissesWhenPointingAway) {
    const TypeParam accel(scene_of({two_layer_mesh()}, {{0, AffineTransform::identity()}}));
    const Ray ray = make_ray({0.25f, 0.5f, 3.0f}, {0, 0, 1});
    const Hit hit = accel.intersect(ray);
    EXPECT_FALSE(hit.is_hit());
    EXPECT_EQ(hit.t, kInf);
    EXPECT_EQ(hit.instance_id, kInvalidId);
    EXPECT_FALSE(accel.occluded(ray));
}

TYPED_TEST(EmbreeReferenceTest, OccludedOnlyWhenHitLiesInSegment) {
    const TypeParam accel(scene_of({two_layer_mesh()}, {{0, AffineTransform::identity()}}));
    const Vec3f org{0.25f, 0.5f, 3.0f}, dir{0, 0, -2};  // hits at t = 1.5 and t = 2
    EXPECT_TRUE(accel.occluded(make_ray(org, dir)));
    EXPECT_TRUE(accel.occluded(make_ray(org, dir, 0.0f, 1.6f)));
    EXPECT_FALSE(accel.occluded(make_ray(org, dir, 0.0f, 1.4f)));
    EXPECT_FALSE(accel.intersect(make_ray(org, dir, 0.0f, 1.4f)).is_hit());
    EXPECT_FALSE(accel.occluded(make_ray(org, dir, 2.1f, kInf)));
    // Starting past the first layer, the closest hit is the second one.
    EXPECT_NEAR(accel.intersect(make_ray(org, dir, 1.6f, kInf)).t, 2.0f, 1e-6f);
}

TYPED_TEST(EmbreeReferenceTest, EmptyOrNanSegmentIsAMiss) {
    const TypeParam accel(scene_of({two_layer_mesh()}, {{0, AffineTransform::identity()}}));
    const Vec3f org{0.25f, 0.5f, 3.0f}, dir{0, 0, -2};
    for (const Ray& ray :
         {make_ray(org, dir, 1.6f, 1.4f), make_ray(org, dir, 0.0f, -kInf),
          make_ray(org, dir, 0.0f, std::nanf("")), make_ray(org, dir, std::nanf(""), kInf)}) {
        EXPECT_FALSE(accel.intersect(ray).is_hit());
        EXPECT_FALSE(accel.occluded(ray));
    }
}

TYPED_TEST(EmbreeReferenceTest, RejectsRaysEmbreeCannotTrace) {
    const TypeParam accel(scene_of({two_layer_mesh()}, {{0, AffineTransform::identity()}}));
    const Vec3f org{0.25f, 0.5f, 3.0f}, dir{0, 0, -2};
    EXPECT_THROW(accel.intersect(make_ray(org, dir, -1.0f, kInf)), Error);
    EXPECT_THROW(accel.occluded(make_ray(org, dir, -1.0f, kInf)), Error);
    EXPECT_THROW(accel.intersect(make_ray({std::nanf(""), 0, 0}, dir)), Error);
    EXPECT_THROW(accel.occluded(make_ray(org, {0, kInf, -1})), Error);
}

TYPED_TEST(EmbreeReferenceTest, TransformedMirroredInstanceHitAtHandComputedT) {
    const AffineTransform to_world = AffineTransform::translate({5, -1, 2}) *
                                     AffineTransform::rotate({1, 2, 3}, 0.8f) *
                                     AffineTransform::scale({2, -3, 0.5f});
    ASSERT_LT(to_world.determinant(), 0.0f);
    // Instance 0 sits far away, so the hit must name instance 1.
    const TypeParam accel(scene_of(
        {two_layer_mesh()}, {{0, AffineTransform::translate({100, 100, 100})}, {0, to_world}}));
    // Aim at the world image of object point (0.25, 0.5, 0) from 2.5 direction lengths away:
    // affine maps keep both t and barycentrics.
    const Vec3f target = to_world.transform_point({0.25f, 0.5f, 0.0f});
    const Vec3f dir = to_world.transform_vector({0.3f, -0.2f, -1.0f});
    const Hit hit = accel.intersect(make_ray(target - 2.5f * dir, dir));
    EXPECT_NEAR(hit.t, 2.5f, 1e-4f);
    EXPECT_EQ(hit.instance_id, 1u);
    EXPECT_EQ(hit.prim_id, 0u);
    EXPECT_NEAR(hit.u, 0.25f, 1e-4f);
    EXPECT_NEAR(hit.v, 0.5f, 1e-4f);
}

TYPED_TEST(EmbreeReferenceTest, SkipsMeshesWithoutTriangles) {
    Mesh empty;
    empty.name = "empty";
    const TypeParam accel(scene_of({empty, two_layer_mesh()}, {{0, AffineTransform::identity()},
                                                               {1, AffineTransform::identity()}}));
    const Hit hit = accel.intersect(make_ray({0.25f, 0.5f, 3.0f}, {0, 0, -1}));
    EXPECT_EQ(hit.instance_id, 1u);
    const TypeParam nothing{Scene{}};
    EXPECT_FALSE(nothing.intersect(make_ray({0, 0, 0}, {0, 0, 1})).is_hit());
}

TYPED_TEST(EmbreeReferenceTest, StatsCountInputAndEmbreeMemory) {
    const Mesh mesh = two_layer_mesh();
    const TypeParam accel(scene_of(
        {mesh}, {{0, AffineTransform::identity()}, {0, AffineTransform::translate({0, 0, 5})}}));
    const AccelStats stats = accel.stats();
    EXPECT_EQ(stats.triangles, 4u);
    EXPECT_EQ(stats.instances, 2u);
    EXPECT_EQ(stats.meshes, 1u);
    EXPECT_GE(stats.build_ms, 0.0);
    ASSERT_TRUE(stats.memory_bytes.has_value());
    // At least one copy of the vertex and index data lives in Embree.
    EXPECT_GE(*stats.memory_bytes,
              mesh.positions.size() * sizeof(Vec3f) + mesh.triangles.size() * sizeof(Triangle));
}

TYPED_TEST(EmbreeReferenceTest, InvalidSceneIsAClearError) {
    const Scene scene = scene_of({two_layer_mesh()}, {{3, AffineTransform::identity()}});
    try {
        const TypeParam accel(scene);
        FAIL() << "an instance of a missing mesh was accepted";
    } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find("Embree"), std::string::npos) << error.what();
        EXPECT_NE(std::string(error.what()).find("mesh 3"), std::string::npos) << error.what();
    }
}

TYPED_TEST(EmbreeReferenceTest, EmbreeCommitErrorReachesTheUser) {
    // Embree accepts an unknown acceleration structure name at device creation and only
    // refuses it when a scene is built.
    EmbreeReferenceSettings settings;
    settings.device_config = "tri_accel=no_such_structure";
    const Scene scene = scene_of({two_layer_mesh()}, {{0, AffineTransform::identity()}});
    try {
        const TypeParam accel(scene, settings);
        FAIL() << "Embree built a scene with an unknown acceleration structure";
    } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find("rtcCommitScene: Embree error RTC_ERROR_"),
                  std::string::npos)
            << error.what();
    }
}

TEST(EmbreeInstancedAccel, RejectsRaysBeyondEmbreeLimitsInObjectSpace) {
    // Scaling by 1e-3 to world means scaling rays by 1e3 into object space: an origin at 1e17
    // is fine for Embree in world space but would reach 1e20 in object space, past Embree's
    // 1.844e18, where its assertion would abort the process.
    const Scene scene =
        scene_of({two_layer_mesh()}, {{0, AffineTransform::scale({1e-3f, 1e-3f, 1e-3f})}});
    const EmbreeInstancedAccel instanced(scene);
    EXPECT_LE(instanced.ray_limits().max_origin_coordinate, 1.844e15f);
    EXPECT_LE(instanced.ray_limits().max_direction_coordinate, 1.844e15f);
    EXPECT_THROW(instanced.intersect(make_ray({1e17f, 0, 0}, {-1, 0, 0})), Error);
    EXPECT_THROW(instanced.occluded(make_ray({0, 0, 1}, {0, 0, -1e17f})), Error);
    // Within the limit the ray reaches Embree (and would abort the test if the limit were
    // too generous).
    EXPECT_FALSE(instanced.intersect(make_ray({1e15f, 0, 0}, {1, 0, 0})).is_hit());
    const EmbreeFlatAccel flat(scene);
    EXPECT_NO_THROW(flat.intersect(make_ray({1e17f, 0, 0}, {-1, 0, 0})));
}

// ---- against brute force, flat against instanced ----------------------------------------

TEST(EmbreeReference, BothMatchBruteForceOnMirroredInstances) {
    const Scene scene = mirrored_instances_scene();
    const BruteForceAccel brute_force(scene);
    const std::vector<Ray> rays = generate_random_rays(scene.bounds(), 1000, 10);
    {
        SCOPED_TRACE("embree-flat");
        expect_agreement(compare_accels(scene, EmbreeFlatAccel(scene), brute_force, rays),
                         kMaxTieFractionProcedural);
    }
    {
        SCOPED_TRACE("embree-instanced");
        expect_agreement(compare_accels(scene, EmbreeInstancedAccel(scene), brute_force, rays),
                         kMaxTieFractionProcedural);
    }
}

TEST(EmbreeReference, FlatAndInstancedAgreeOnMirroredInstances) {
    const Scene scene = mirrored_instances_scene();
    ASSERT_GT(std::count_if(scene.instances.begin(), scene.instances.end(),
                            [](const Instance& i) { return i.object_to_world.determinant() < 0; }),
              0);
    expect_flat_and_instanced_agree(scene, 11, kMaxTieFractionProcedural);
}

TEST(EmbreeReference, BuildSettingsDoNotChangeHits) {
    const Scene scene = mirrored_instances_scene();
    const EmbreeFlatAccel reference(scene);
    const std::vector<Ray> rays = generate_random_rays(scene.bounds(), 2000, 12);
    for (EmbreeBuildQuality quality :
         {EmbreeBuildQuality::low, EmbreeBuildQuality::medium, EmbreeBuildQuality::high}) {
        for (bool is_robust : {false, true}) {
            SCOPED_TRACE("quality " + std::to_string(static_cast<int>(quality)) + " robust " +
                         std::to_string(is_robust));
            EmbreeReferenceSettings settings;
            settings.build_quality = quality;
            settings.is_robust = is_robust;
            expect_agreement(
                compare_accels(scene, reference, EmbreeFlatAccel(scene, settings), rays),
                kMaxTieFractionProcedural);
            expect_agreement(
                compare_accels(scene, reference, EmbreeInstancedAccel(scene, settings), rays),
                kMaxTieFractionProcedural);
        }
    }
}

TEST(EmbreeReference, FlatAndInstancedAgreeOnDefaultScene) {
    expect_flat_and_instanced_agree(make_default_scene(), 7, kMaxTieFractionProcedural);
}

std::vector<std::string> shared_scene_files() {
    std::vector<std::string> files;
    const std::filesystem::path folder(REBRAID_SHARED_SCENES);
    std::error_code error;
    if (!std::filesystem::is_directory(folder, error)) return files;
    for (const auto& entry : std::filesystem::directory_iterator(folder, error))
        if (entry.path().extension() == ".glb") files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    return files;
}

TEST(EmbreeReference, SharedScenesFolderHoldsAtLeastNineScenes) {
    EXPECT_GE(shared_scene_files().size(), 9u) << "folder " << REBRAID_SHARED_SCENES;
}

class SharedSceneTest : public ::testing::TestWithParam<std::string> {};
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(SharedSceneTest);

TEST_P(SharedSceneTest, FlatAndInstancedAgreeOnRandomRays) {
    const Scene scene = load_gltf_scene(GetParam());
    // A different seed per file, derived from its name so the choice is stable.
    std::uint64_t seed = 1469598103934665603ull;
    for (char c : std::filesystem::path(GetParam()).filename().string())
        seed = (seed ^ static_cast<unsigned char>(c)) * 1099511628211ull;
    expect_flat_and_instanced_agree(scene, seed, kMaxTieFractionRealModels);
}

INSTANTIATE_TEST_SUITE_P(EmbreeReference, SharedSceneTest,
                         ::testing::ValuesIn(shared_scene_files()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             std::string name = std::filesystem::path(info.param).stem().string();
                             for (char& c : name)
                                 if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                             return name;
                         });

}  // namespace
}  // namespace rebraid::glue
