// rebraid::EmbreeAccel against rtcIntersect1/rtcOccluded1 on the same RTCScene: the default
// scene and every shared scene fed to Embree as an application would, updates, the
// user-geometry mode, Embree's ray conventions and what it refuses; and the hit-attribute
// kernel (glue::embree_hit_attributes) bit for bit against Embree. This executable links
// rebraid::embree_dropin, whose interposer sees its Embree calls, as in an application.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/core/triangle_test.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/embree_dropin_app.h"

namespace rebraid {
namespace {

using namespace rebraid::test;

// ---- EmbreeAccel against Embree ------------------------------------------------------------

TEST(EmbreeAccel, MatchesEmbreeOnDefaultScene) {
    Device app;
    const Scene scene = make_default_scene();
    const auto embree_scene = feed_to_embree(app.device, scene, /*flatten_every=*/7);
    const EmbreeAccel accel(embree_scene->top);
    EXPECT_EQ(accel.converted_scene().scene.instances.size(), scene.instances.size());
    expect_accel_matches_embree(embree_scene->top, accel, 1);
}

TEST(EmbreeAccel, MatchesEmbreeWithRtcBuildBvhObjectBuilder) {
    Device app;
    const Scene scene = make_default_scene();
    const auto embree_scene = feed_to_embree(app.device, scene, /*flatten_every=*/5);
    const EmbreeAccel accel(embree_scene->top,
                            {.object_builder = EmbreeAccelObjectBuilder::embree});
    expect_accel_matches_embree(embree_scene->top, accel, 2);
}

// Embree's robust mode is watertight, its default mode runs the Möller test: EmbreeAccel
// follows the scene's RTC_SCENE_FLAG_ROBUST at construction and at every update.
TEST(EmbreeAccel, TracesRobustScenesWithTheWatertightTest) {
    Device app;
    const Scene scene = make_default_scene();
    const auto embree_scene = feed_to_embree(app.device, scene, /*flatten_every=*/7);
    EXPECT_EQ(EmbreeAccel(embree_scene->top).accel().triangle_test(), TriangleTest::moller);
    rtcSetSceneFlags(embree_scene->top, RTC_SCENE_FLAG_ROBUST);
    rtcCommitScene(embree_scene->top);
    EmbreeAccel accel(embree_scene->top);
    EXPECT_EQ(accel.accel().triangle_test(), TriangleTest::watertight);
    EXPECT_TRUE(accel.converted_scene().is_robust);
    rtcSetSceneFlags(embree_scene->top, RTC_SCENE_FLAG_NONE);
    rtcCommitScene(embree_scene->top);
    accel.update();
    EXPECT_EQ(accel.accel().triangle_test(), TriangleTest::moller);
    EXPECT_FALSE(accel.converted_scene().is_robust);
}

class EmbreeAccelOnSharedScene : public testing::TestWithParam<std::string> {};

TEST_P(EmbreeAccelOnSharedScene, MatchesEmbree) {
    Device app;
    const Scene scene = load_gltf_scene(std::string(REBRAID_SHARED_SCENES) + "/" + GetParam());
    const auto embree_scene = feed_to_embree(app.device, scene);
    const EmbreeAccel accel(embree_scene->top);
    expect_accel_matches_embree(embree_scene->top, accel, 3);
}

INSTANTIATE_TEST_SUITE_P(SharedScenes, EmbreeAccelOnSharedScene,
                         testing::ValuesIn(test::shared_scene_files()),
                         [](const testing::TestParamInfo<std::string>& info) {
                             return test::test_name_of(info.param);
                         });

// A scene whose instances repeat little is traced through a world tree (world_tree.h) after a
// full build, kept by a commit that changes nothing, and given up for the merged top level
// once an instance moves; Embree's answers every time.
TEST(EmbreeAccel, TracesAWorldTreeUntilInstancesMove) {
    Device app;
    const Scene scene =
        load_gltf_scene(std::string(REBRAID_SHARED_SCENES) + "/motion_capture_rom.glb");
    const auto embree_scene = feed_to_embree(app.device, scene);
    EmbreeAccel accel(embree_scene->top);
    EXPECT_TRUE(accel.accel().merged_top_level().is_world_tree);
    expect_accel_matches_embree(embree_scene->top, accel, 21);

    rtcCommitScene(embree_scene->top);
    const EmbreeUpdateReport unchanged = accel.update();
    EXPECT_FALSE(unchanged.is_full_rebuild);
    EXPECT_EQ(unchanged.meshes_unchanged, accel.converted_scene().scene.meshes.size());
    EXPECT_TRUE(accel.accel().merged_top_level().is_world_tree);

    const RTCGeometry moved = rtcGetGeometry(embree_scene->top, 1);
    const AffineTransform new_transform =
        AffineTransform::translate({0.05f, 0.1f, 0.0f}) * scene.instances[1].object_to_world;
    rtcSetGeometryTransform(moved, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, &new_transform);
    rtcCommitGeometry(moved);
    rtcCommitScene(embree_scene->top);
    accel.update();
    EXPECT_FALSE(accel.accel().merged_top_level().is_world_tree);
    expect_accel_matches_embree(embree_scene->top, accel, 22);
}

/// Random triangles of widely varying size behind a random rotation, scale and translation:
/// every hit rtcIntersect1 reports must be reproduced to the last bit by
/// glue::embree_hit_attributes with Embree's world-to-object map and the arithmetic of the
/// kernels the device runs.
void expect_bit_identical_attributes(const char* device_config,
                                     glue::EmbreeKernelArithmetic arithmetic) {
    const RTCDevice device = rtcNewDevice(device_config);
    ASSERT_NE(device, nullptr);
    Random random(11);
    Mesh mesh;
    for (std::uint32_t t = 0; t < 300; ++t) {
        const Vec3f center{random.next_float(-20, 20), random.next_float(-20, 20),
                           random.next_float(-20, 20)};
        const float size = std::exp(random.next_float(-3, 3));
        for (int corner = 0; corner < 3; ++corner)
            mesh.positions.push_back(center + Vec3f{random.next_float(-size, size),
                                                    random.next_float(-size, size),
                                                    random.next_float(-size, size)});
        mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    SharedMemory memory;
    const RTCScene mesh_scene = rtcNewScene(device);
    const RTCGeometry geometry =
        make_triangle_geometry(device, mesh, BufferPath::new_geometry_buffer, memory);
    rtcAttachGeometry(mesh_scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(mesh_scene);
    std::size_t hits = 0;
    for (int transform_index = 0; transform_index < 20; ++transform_index) {
        const Vec3f axis = normalize(
            Vec3f{random.next_float(-1, 1), random.next_float(-1, 1), random.next_float(0.1f, 1)});
        const AffineTransform object_to_world =
            AffineTransform::translate({random.next_float(-500, 500), random.next_float(-500, 500),
                                        random.next_float(-50, 50)}) *
            AffineTransform::rotate(axis, random.next_float(0, 6.28f)) *
            AffineTransform::scale({random.next_float(0.1f, 3), random.next_float(0.1f, 3),
                                    random.next_float(0.1f, 3)});
        const RTCScene top = rtcNewScene(device);
        const RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(instance, mesh_scene);
        rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, &object_to_world);
        rtcCommitGeometry(instance);
        rtcAttachGeometry(top, instance);
        rtcReleaseGeometry(instance);
        rtcCommitScene(top);
        const AffineTransform world_to_object = glue::embree_world_to_object(object_to_world);
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        for (int r = 0; r < 200; ++r) {
            // From a random origin towards a random point of a random triangle.
            const auto corners = mesh.corners(random.next_below(300));
            const float a = random.next_float01(), b = random.next_float01() * (1 - a);
            const Vec3f target = object_to_world.transform_point(
                corners[0] + (corners[1] - corners[0]) * a + (corners[2] - corners[0]) * b);
            const Vec3f org = object_to_world.translation + Vec3f{random.next_float(-200, 200),
                                                                  random.next_float(-200, 200),
                                                                  random.next_float(-200, 200)};
            const Ray ray{org, 0.0f, (target - org) * random.next_float(0.5f, 2.0f), kInf};
            RTCRayHit rayhit = make_rayhit(ray);
            rtcIntersect1(top, &context, &rayhit);
            if (!is_hit(rayhit)) continue;
            ++hits;
            const auto ours = glue::embree_hit_attributes(
                ray, &world_to_object, mesh.corners(rayhit.hit.primID), arithmetic);
            ASSERT_TRUE(ours.has_value()) << "transform " << transform_index << " ray " << r;
            EXPECT_EQ(ours->t, rayhit.ray.tfar) << "transform " << transform_index << " ray " << r;
            EXPECT_EQ(ours->u, rayhit.hit.u) << "transform " << transform_index << " ray " << r;
            EXPECT_EQ(ours->v, rayhit.hit.v) << "transform " << transform_index << " ray " << r;
            EXPECT_EQ(ours->geometry_normal.x, rayhit.hit.Ng_x);
            EXPECT_EQ(ours->geometry_normal.y, rayhit.hit.Ng_y);
            EXPECT_EQ(ours->geometry_normal.z, rayhit.hit.Ng_z);
        }
        rtcReleaseScene(top);
    }
    EXPECT_GT(hits, 20u * 200u * 9u / 10u);
    rtcReleaseScene(mesh_scene);
    rtcReleaseDevice(device);
}

TEST(EmbreeHitAttributes, ReproduceEmbreesDefaultKernelsBitForBit) {
    // The kernels a default device picks on this CPU: AVX-512 ones where it has them.
    expect_bit_identical_attributes(nullptr, glue::detect_embree_kernel_arithmetic());
}

TEST(EmbreeHitAttributes, ReproduceEmbreesAvx2KernelsBitForBit) {
    if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma"))
        GTEST_SKIP() << "no AVX2 and FMA on this CPU";
    expect_bit_identical_attributes("isa=avx2", glue::EmbreeKernelArithmetic::fused);
}

/// Expects `a` and `b` to be the same attributes to the last bit.
void expect_same_attribute_bits(const glue::EmbreeHitAttributes& a,
                                const glue::EmbreeHitAttributes& b) {
    EXPECT_EQ(std::bit_cast<std::uint32_t>(a.t), std::bit_cast<std::uint32_t>(b.t));
    EXPECT_EQ(std::bit_cast<std::uint32_t>(a.u), std::bit_cast<std::uint32_t>(b.u));
    EXPECT_EQ(std::bit_cast<std::uint32_t>(a.v), std::bit_cast<std::uint32_t>(b.v));
    EXPECT_EQ(a.geometry_normal.x, b.geometry_normal.x);
    EXPECT_EQ(a.geometry_normal.y, b.geometry_normal.y);
    EXPECT_EQ(a.geometry_normal.z, b.geometry_normal.z);
}

// The SIMD kernels' Möller test computes Embree's own terms when rays enter instances through
// Embree's world-to-object maps: finishing them (embree_fused_attributes_from_terms) gives
// what the full recomputation gives, bit for bit, in both fused arithmetics. The portable
// kernels and the watertight test give no terms.
TEST(EmbreeHitAttributes, TraversalTermsFinishToTheRecomputedAttributesBitForBit) {
    const Scene scene = make_default_scene();
    InstancedAccel accel = build_rebraid_accel(scene);
    std::vector<AffineTransform> maps;
    for (const Instance& instance : scene.instances)
        maps.push_back(glue::embree_world_to_object(instance.object_to_world));
    accel.set_world_to_object(maps);
    const std::vector<Ray> rays = generate_random_rays(scene.bounds(), 4000, 5);
    for (SimdLevel level : runnable_simd_levels()) {
        accel.set_simd_level(level);
        for (TriangleTest test : {TriangleTest::moller, TriangleTest::watertight}) {
            SCOPED_TRACE(std::string(simd_level_name(level)) + " " +
                         std::string(triangle_test_name(test)));
            accel.set_triangle_test(test);
            const bool gives_terms = level != SimdLevel::portable && test == TriangleTest::moller;
            std::size_t compared = 0;
            for (const Ray& ray : rays) {
                const LocatedHit located = accel.intersect_located(ray);
                if (!located.hit.is_hit()) continue;
                ASSERT_EQ(located.triangle.has_moller_terms, gives_terms);
                if (!gives_terms) continue;
                const bool is_identity = scene.instances[located.hit.instance_id].object_to_world ==
                                         AffineTransform::identity();
                const TriangleVerts c = located.triangle.corners();
                for (auto arithmetic : {glue::EmbreeKernelArithmetic::fused,
                                        glue::EmbreeKernelArithmetic::fused_rcp14}) {
                    if (arithmetic == glue::EmbreeKernelArithmetic::fused_rcp14 &&
                        !__builtin_cpu_supports("avx512f"))
                        continue;
                    // Finished as the drop-in finishes them, from the arithmetic's estimate.
                    const float abs_den = located.triangle.moller_terms.abs_den;
                    const auto finished = glue::embree_fused_attributes_from_terms(
                        located.triangle.moller_terms,
                        arithmetic == glue::EmbreeKernelArithmetic::fused
                            ? glue::embree_reciprocal_estimate_12(abs_den)
                            : glue::embree_reciprocal_estimate_14(abs_den));
                    const auto recomputed = glue::embree_hit_attributes(
                        ray, is_identity ? nullptr : &maps[located.hit.instance_id],
                        {c.v0, c.v1, c.v2}, arithmetic);
                    ASSERT_EQ(finished.has_value(), recomputed.has_value());
                    if (!finished) continue;
                    ++compared;
                    expect_same_attribute_bits(*finished, *recomputed);
                }
            }
            if (gives_terms) {
                EXPECT_GT(compared, 400u);
            }
        }
    }
}

TEST(EmbreeHitAttributes, ReproduceEmbreesSse42KernelsBitForBit) {
    if (!__builtin_cpu_supports("sse4.2")) GTEST_SKIP() << "no SSE4.2 on this CPU";
    expect_bit_identical_attributes("isa=sse4.2", glue::EmbreeKernelArithmetic::separate);
}

void set_lane(RTCRay4& packet, unsigned int lane, const RTCRay& ray) {
    packet.org_x[lane] = ray.org_x;
    packet.org_y[lane] = ray.org_y;
    packet.org_z[lane] = ray.org_z;
    packet.tnear[lane] = ray.tnear;
    packet.dir_x[lane] = ray.dir_x;
    packet.dir_y[lane] = ray.dir_y;
    packet.dir_z[lane] = ray.dir_z;
    packet.time[lane] = ray.time;
    packet.tfar[lane] = ray.tfar;
    packet.mask[lane] = ray.mask;
    packet.id[lane] = ray.id;
    packet.flags[lane] = ray.flags;
}

TEST(EmbreeAccel, UserGeometrySceneGivesTheSameAnswersAsDirectCalls) {
    Device app;
    const Scene scene = make_default_scene();
    const auto embree_scene = feed_to_embree(app.device, scene, /*flatten_every=*/3);
    const EmbreeAccel accel(embree_scene->top);
    const EmbreeUserGeometryScene rebraided(accel);
    const std::vector<Ray> rays = generate_random_rays(accel.bounds(), kRayCount, 4);
    const Answers direct = trace_accel(accel, rays);
    const Answers through_embree = trace_embree(rebraided.get(), rays);
    std::size_t hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const RTCRayHit& d = direct.hits[i];
        const RTCRayHit& e = through_embree.hits[i];
        hits += is_hit(d);
        ASSERT_EQ(std::memcmp(&d, &e, sizeof(RTCRayHit)), 0) << "ray " << i;
        ASSERT_EQ(direct.occluded_tfar[i], through_embree.occluded_tfar[i]) << "ray " << i;
    }
    EXPECT_GT(hits, rays.size() / 50);
    // And so the user-geometry scene matches Embree on the original scene.
    expect_same_as_embree(trace_embree(embree_scene->top, rays), through_embree, accel.bounds());

    // Packets of 4 go through the callbacks' N > 1 path.
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t first = 0; first + 4 <= 400; first += 4) {
        RTCRayHit4 packet{};
        RTCRay4 occlusion{};
        int valid[4] = {-1, -1, 0, -1};  // one inactive lane
        for (unsigned int lane = 0; lane < 4; ++lane) {
            const RTCRayHit single = make_rayhit(rays[first + lane]);
            set_lane(packet.ray, lane, single.ray);
            rtcCopyHitToHitN(reinterpret_cast<RTCHitN*>(&packet.hit), &single.hit, 4, lane);
            set_lane(occlusion, lane, single.ray);
        }
        rtcIntersect4(valid, rebraided.get(), &context, &packet);
        rtcOccluded4(valid, rebraided.get(), &context, &occlusion);
        for (unsigned int lane = 0; lane < 4; ++lane) {
            const RTCRayHit& d = direct.hits[first + lane];
            if (valid[lane] == 0) {
                EXPECT_EQ(packet.hit.geomID[lane], RTC_INVALID_GEOMETRY_ID);
                continue;
            }
            EXPECT_EQ(packet.hit.geomID[lane], d.hit.geomID) << "ray " << first + lane;
            EXPECT_EQ(packet.hit.primID[lane], d.hit.primID);
            EXPECT_EQ(packet.hit.instID[0][lane], d.hit.instID[0]);
            EXPECT_EQ(packet.ray.tfar[lane], d.ray.tfar);
            EXPECT_EQ(packet.hit.u[lane], d.hit.u);
            EXPECT_EQ(occlusion.tfar[lane], direct.occluded_tfar[first + lane]);
        }
    }
}

class EmbreeAccelUpdate : public testing::TestWithParam<UpdateStrategy> {};

TEST_P(EmbreeAccelUpdate, AfterMovingAnInstanceAndDeformingAMeshMatchesEmbree) {
    Device app;
    Scene scene = make_default_scene();
    // The application deforms vertex buffers in place, whichever way it made them.
    const auto embree_scene = feed_to_embree(app.device, scene, /*flatten_every=*/9);
    EmbreeAccelSettings settings;
    settings.object_update.strategy = GetParam();
    EmbreeAccel accel(embree_scene->top, settings);

    const auto snapshot = glue::snapshot_registered_scene(embree_scene->top);
    ASSERT_TRUE(snapshot.has_value());
    const auto& top = snapshot->scenes.at(embree_scene->top);
    // Move the instance with geomID 1 (an instance: flattening took geomID 0).
    const RTCGeometry moved = top.geometries.at(1);
    ASSERT_EQ(snapshot->geometries.at(moved).type, RTC_GEOMETRY_TYPE_INSTANCE);
    const AffineTransform new_transform = AffineTransform::translate({0.5f, 1.0f, -0.25f}) *
                                          AffineTransform::rotate({0, 1, 0}, 0.7f) *
                                          scene.instances[1].object_to_world;
    rtcSetGeometryTransform(moved, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, &new_transform);
    rtcCommitGeometry(moved);

    // Deform the mesh of instance 2 (in its own scene, geometry 0): a wave along y.
    const RTCScene deformed_scene = snapshot->geometries.at(top.geometries.at(2)).instanced_scene;
    const RTCGeometry deformed = snapshot->scenes.at(deformed_scene).geometries.at(0);
    const auto& view = snapshot->geometries.at(deformed).buffers.at({RTC_BUFFER_TYPE_VERTEX, 0});
    auto* vertex_bytes = const_cast<std::byte*>(view.data);
    for (std::size_t i = 0; i < view.item_count; ++i) {
        float* p = reinterpret_cast<float*>(vertex_bytes + i * view.byte_stride);
        p[1] += 0.3f * std::sin(4.0f * p[0]);
    }
    rtcUpdateGeometryBuffer(deformed, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(deformed);
    rtcCommitScene(deformed_scene);
    rtcCommitScene(embree_scene->top);

    for (int frame = 0; frame < 2; ++frame) {
        if (frame == 1) {  // deform again: the updater's second step (auto: in place)
            for (std::size_t i = 0; i < view.item_count; ++i) {
                float* p = reinterpret_cast<float*>(vertex_bytes + i * view.byte_stride);
                p[0] += 0.1f * std::cos(3.0f * p[2]);
            }
            rtcUpdateGeometryBuffer(deformed, RTC_BUFFER_TYPE_VERTEX, 0);
            rtcCommitGeometry(deformed);
            rtcCommitScene(deformed_scene);
            rtcCommitScene(embree_scene->top);
        }
        const EmbreeUpdateReport report = accel.update();
        EXPECT_FALSE(report.is_full_rebuild);
        EXPECT_EQ(report.meshes_rebuilt + report.meshes_refit, 1u);
        if (GetParam() == UpdateStrategy::refit) {
            EXPECT_EQ(report.meshes_refit, 1u);
        }
        if (GetParam() == UpdateStrategy::rebuild) {
            EXPECT_EQ(report.meshes_rebuilt, 1u);
        }
        EXPECT_EQ(report.meshes_unchanged, accel.converted_scene().scene.meshes.size() - 1);
        expect_accel_matches_embree(embree_scene->top, accel, 5 + frame);
    }
}

INSTANTIATE_TEST_SUITE_P(Strategies, EmbreeAccelUpdate,
                         testing::Values(UpdateStrategy::refit, UpdateStrategy::rebuild,
                                         UpdateStrategy::automatic),
                         [](const testing::TestParamInfo<UpdateStrategy>& info) {
                             return std::string(update_strategy_name(info.param));
                         });

TEST(EmbreeAccel, UpdateAfterAttachingAndDisablingRebuildsAndMatchesEmbree) {
    Device app;
    const Scene scene = make_default_scene();
    const auto embree_scene = feed_to_embree(app.device, scene);
    EmbreeAccel accel(embree_scene->top);
    SharedMemory memory;
    const AffineTransform place = AffineTransform::translate(accel.bounds().center());
    const RTCGeometry added =
        make_triangle_geometry(app.device, scene.meshes[0], BufferPath::new_buffer, memory, &place);
    rtcAttachGeometry(embree_scene->top, added);
    rtcReleaseGeometry(added);
    const RTCGeometry disabled = rtcGetGeometry(embree_scene->top, 3);
    rtcDisableGeometry(disabled);
    rtcCommitScene(embree_scene->top);

    const EmbreeUpdateReport report = accel.update();
    EXPECT_TRUE(report.is_full_rebuild);
    EXPECT_EQ(accel.converted_scene().scene.instances.size(), scene.instances.size());
    expect_accel_matches_embree(embree_scene->top, accel, 6);
}

// Rays whose line misses the padded scene bounds return before the traversal: the rays that
// test that early exit's edges. From far away (up to 1,000 diagonals) aimed at the centres of the
// scene's triangles, which they must reach; starting just inside a face of the scene's box and
// running parallel to it (zero direction components); with tiny direction components; and aimed
// just past the box's corners.
TEST(EmbreeAccel, RaysNearAndFarFromTheSceneBoundsMatchEmbree) {
    Device app;
    const Scene scene = make_default_scene();
    const auto embree_scene = feed_to_embree(app.device, scene, /*flatten_every=*/7);
    const EmbreeAccel accel(embree_scene->top);
    const BBox3f bounds = accel.bounds();
    const float diagonal = length(bounds.max - bounds.min);
    Random random(11);
    const auto random_unit = [&] {
        const Vec3f v{random.next_float(-1, 1), random.next_float(-1, 1), random.next_float(-1, 1)};
        return length(v) > 1e-3f ? v / length(v) : Vec3f{0, 0, 1};
    };
    const auto inside = [&] {
        Vec3f p;
        for (int a = 0; a < 3; ++a) p[a] = random.next_float(bounds.min[a], bounds.max[a]);
        return p;
    };
    std::vector<Ray> rays;
    for (int i = 0; i < 2000; ++i) {  // from far away at a triangle's centre
        const Instance& instance = scene.instances[random.next_below(scene.instances.size())];
        const Mesh& mesh = scene.meshes[instance.mesh_id];
        const auto corners = mesh.corners(random.next_below(mesh.triangles.size()));
        const Vec3f centre =
            instance.object_to_world.transform_point((corners[0] + corners[1] + corners[2]) / 3.0f);
        const Vec3f origin =
            centre + random_unit() * (diagonal * std::exp2(random.next_float(0.0f, 10.0f)));
        rays.push_back({origin, 0.0f, centre - origin, kInf});
    }
    for (int i = 0; i < 2000; ++i) {  // just inside a face of the box, parallel to it
        const int axis = int(random.next_below(3));
        Vec3f origin = inside();
        const float inset = 1e-3f * (bounds.max[axis] - bounds.min[axis]);
        origin[axis] =
            random.next_below(2) == 0 ? bounds.min[axis] + inset : bounds.max[axis] - inset;
        Vec3f dir = random_unit();
        dir[axis] = 0.0f;
        if (length(dir) == 0.0f) dir[(axis + 1) % 3] = 1.0f;
        rays.push_back({origin, 0.0f, dir, kInf});
    }
    for (int i = 0; i < 2000; ++i) {  // tiny direction components, from outside the box
        Vec3f dir = random_unit();
        const int keep = int(random.next_below(3));  // one component keeps its size
        for (int a = 0; a < 3; ++a)
            if (a != keep && random.next_below(2) == 0) dir[a] = std::copysign(1e-20f, dir[a]);
        const Vec3f target = inside();
        rays.push_back({target - dir * (2.0f * diagonal / length(dir)), 0.0f, dir, kInf});
    }
    for (int i = 0; i < 2000; ++i) {  // just past a corner of the box
        Vec3f corner;
        for (int a = 0; a < 3; ++a)
            corner[a] = random.next_below(2) == 0 ? bounds.min[a] : bounds.max[a];
        const Vec3f past = corner + random_unit() * (diagonal * 1e-4f);
        const Vec3f origin = past + random_unit() * diagonal;
        rays.push_back({origin, 0.0f, past - origin, kInf});
    }
    const Answers embree = trace_embree(embree_scene->top, rays);
    expect_same_as_embree(embree, trace_accel(accel, rays), bounds);
    std::size_t far_hits = 0;
    for (std::size_t i = 0; i < 2000; ++i) far_hits += is_hit(embree.hits[i]);
    EXPECT_GT(far_hits, 1900u);  // the far rays do reach the scene
}

// ---- Ray conventions -----------------------------------------------------------------------

TEST(EmbreeAccel, FollowsEmbreeRayConventions) {
    Device app;
    SharedMemory memory;
    const RTCScene scene = rtcNewScene(app.device);
    const RTCGeometry triangle =
        make_triangle_geometry(app.device, one_triangle(), BufferPath::shared_buffer, memory);
    rtcAttachGeometryByID(scene, triangle, 4);
    rtcReleaseGeometry(triangle);
    rtcCommitScene(scene);
    const EmbreeAccel accel(scene);
    const Ray towards{{0.25f, 0.25f, 1.0f}, 0.0f, {0.0f, 0.0f, -2.0f}, kInf};

    RTCRayHit hit = make_rayhit(towards);
    hit.hit.instID[0] = 77;  // Embree overwrites it for a hit outside instances
    accel.intersect1(hit);
    EXPECT_EQ(hit.hit.geomID, 4u);
    EXPECT_EQ(hit.hit.primID, 0u);
    EXPECT_EQ(hit.hit.instID[0], RTC_INVALID_GEOMETRY_ID);
    EXPECT_FLOAT_EQ(hit.ray.tfar, 0.5f);  // t in units of the unnormalised direction
    EXPECT_FLOAT_EQ(hit.hit.u, 0.25f);
    EXPECT_FLOAT_EQ(hit.hit.v, 0.25f);
    EXPECT_FLOAT_EQ(hit.hit.Ng_z, 1.0f);  // unnormalised: twice the triangle's area

    // A miss, an inactive ray and a ray with mask 0 leave the ray and hit untouched.
    for (const RTCRayHit& before : {make_rayhit({{5, 5, 1}, 0, {0, 0, -1}, kInf}),
                                    make_rayhit({{0.25f, 0.25f, 1}, 2.0f, {0, 0, -1}, 1.5f}), [&] {
                                        RTCRayHit masked = make_rayhit(towards);
                                        masked.ray.mask = 0;
                                        return masked;
                                    }()}) {
        RTCRayHit after = before;
        accel.intersect1(after);
        EXPECT_EQ(std::memcmp(&before, &after, sizeof(RTCRayHit)), 0);
        RTCRay ray = before.ray;
        accel.occluded1(ray);
        EXPECT_EQ(std::memcmp(&before.ray, &ray, sizeof(RTCRay)), 0);
    }
    RTCRay occluded = make_rayhit(towards).ray;
    accel.occluded1(occluded);
    EXPECT_EQ(occluded.tfar, -kInf);
    RTCRay short_ray = make_rayhit({{0.25f, 0.25f, 1}, 0, {0, 0, -1}, 0.5f}).ray;
    accel.occluded1(short_ray);
    EXPECT_EQ(short_ray.tfar, 0.5f);
    rtcReleaseScene(scene);
}

TEST(EmbreeAccel, SkipsTrianglesEmbreeIgnores) {
    Device app;
    Mesh mesh;
    // Triangle 0 is fine, triangle 1 indexes past the vertices, triangle 2 has a NaN vertex.
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {std::nanf(""), 0, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 1, 9}, {3, 1, 2}};
    SharedMemory memory;
    const RTCScene scene = rtcNewScene(app.device);
    const RTCGeometry geometry =
        make_triangle_geometry(app.device, mesh, BufferPath::shared_geometry_buffer, memory);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene);
    const EmbreeAccel accel(scene);
    // Rays straight down onto the z = 0 plane around the triangles.
    std::vector<Ray> rays;
    for (int j = 0; j < 40; ++j)
        for (int i = 0; i < 40; ++i)
            rays.push_back({{-0.2f + 0.0357f * float(i), -0.2f + 0.0357f * float(j), 1.0f},
                            0.0f,
                            {0.0f, 0.0f, -1.0f},
                            kInf});
    const Answers embree = trace_embree(scene, rays);
    const Answers ours = trace_accel(accel, rays);
    for (std::size_t i = 0; i < rays.size(); ++i) {
        EXPECT_NE(ours.hits[i].hit.primID, 1u);
        EXPECT_NE(ours.hits[i].hit.primID, 2u);
    }
    expect_same_as_embree(embree, ours, {{0, 0, 0}, {1, 1, 0}});
    rtcReleaseScene(scene);
}

// ---- What EmbreeAccel refuses --------------------------------------------------------------

/// Expects building an EmbreeAccel over `scene` to throw a message containing every part.
void expect_refused(RTCScene scene, const std::vector<std::string>& parts) {
    try {
        const EmbreeAccel accel(scene);
        ADD_FAILURE() << "EmbreeAccel accepted the scene";
    } catch (const Error& error) {
        for (const std::string& part : parts)
            EXPECT_NE(std::string(error.what()).find(part), std::string::npos)
                << "'" << error.what() << "' does not mention '" << part << "'";
    }
}

TEST(EmbreeAccel, RefusesUnsupportedGeometryNamingIt) {
    Device app;
    SharedMemory memory;
    const RTCScene scene = rtcNewScene(app.device);
    const RTCGeometry triangle =
        make_triangle_geometry(app.device, one_triangle(), BufferPath::new_geometry_buffer, memory);
    rtcAttachGeometry(scene, triangle);
    rtcReleaseGeometry(triangle);
    const RTCGeometry quads = rtcNewGeometry(app.device, RTC_GEOMETRY_TYPE_QUAD);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(quads, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 4));
    const float quad_vertices[12] = {0, 0, 2, 1, 0, 2, 1, 1, 2, 0, 1, 2};
    std::copy(quad_vertices, quad_vertices + 12, vertices);
    auto* indices = static_cast<std::uint32_t*>(
        rtcSetNewGeometryBuffer(quads, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 16, 1));
    for (std::uint32_t i = 0; i < 4; ++i) indices[i] = i;
    rtcCommitGeometry(quads);
    rtcAttachGeometryByID(scene, quads, 8);
    rtcReleaseGeometry(quads);
    rtcCommitScene(scene);
    expect_refused(scene, {"geometry 8", "RTC_GEOMETRY_TYPE_QUAD", "not supported"});
    rtcReleaseScene(scene);
}

TEST(EmbreeAccel, RefusesMultiLevelInstancingMotionBlurMasksAndUncommittedScenes) {
    Device app;
    SharedMemory memory;
    auto triangle_scene = [&] {
        const RTCScene scene = rtcNewScene(app.device);
        const RTCGeometry triangle = make_triangle_geometry(
            app.device, one_triangle(), BufferPath::new_geometry_buffer, memory);
        rtcAttachGeometry(scene, triangle);
        rtcReleaseGeometry(triangle);
        rtcCommitScene(scene);
        return scene;
    };
    auto instance_of = [&](RTCScene scene) {
        const RTCGeometry instance = rtcNewGeometry(app.device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(instance, scene);
        rtcCommitGeometry(instance);
        return instance;
    };
    // Two levels of instancing (Embree 3 is built for one).
    const RTCScene leaf = triangle_scene();
    const RTCScene middle = rtcNewScene(app.device);
    const RTCGeometry inner_instance = instance_of(leaf);
    rtcAttachGeometryByID(middle, inner_instance, 2);
    rtcReleaseGeometry(inner_instance);
    rtcCommitScene(middle);
    const RTCScene top = rtcNewScene(app.device);
    const RTCGeometry outer_instance = instance_of(middle);
    rtcAttachGeometry(top, outer_instance);
    rtcReleaseGeometry(outer_instance);
    rtcCommitScene(top);
    expect_refused(top, {"geometry 2", "one level of instancing"});

    // Motion blur.
    const RTCScene blurred = triangle_scene();
    rtcSetGeometryTimeStepCount(rtcGetGeometry(blurred, 0), 2);
    expect_refused(blurred, {"geometry 0", "motion blur"});

    // A geometry mask (this Embree build supports ray masks).
    const RTCScene masked = triangle_scene();
    rtcSetGeometryMask(rtcGetGeometry(masked, 0), 2);
    if (rtcGetDeviceProperty(app.device, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0)
        expect_refused(masked, {"geometry 0", "mask 2"});

    // Attached after the last commit.
    const RTCScene changed = triangle_scene();
    const RTCGeometry late =
        make_triangle_geometry(app.device, one_triangle(), BufferPath::new_geometry_buffer, memory);
    rtcAttachGeometry(changed, late);
    rtcReleaseGeometry(late);
    expect_refused(changed, {"since its last rtcCommitScene"});

    for (RTCScene scene : {leaf, middle, top, blurred, masked, changed}) rtcReleaseScene(scene);
}

}  // namespace
}  // namespace rebraid
