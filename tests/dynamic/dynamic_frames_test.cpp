// Structures that follow an animation (rebraid/dynamic_scene*.h, embree_glue/
// embree_dynamic_scene.h) against Embree built from scratch on the same deformed frame.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_bvh_builder.h"
#include "embree_glue/reference/embree_dynamic_scene.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/dynamic/dynamic_scene.h"
#include "rebraid/dynamic/dynamic_scene_accel.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/generators/twisting_object.h"
#include "rebraid/io/gltf_animation.h"
#include "rebraid/io/gltf_dynamic_object.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/io/ray_file.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/bvh_stats.h"
#include "support/containment.h"
#include "support/gltf_animation_files.h"
#include "support/hit_comparison.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

constexpr int kFrameCount = 4;
constexpr float kTimeStep = 0.37f;  // not a divisor of the period: every frame differs

constexpr DynamicTop kDynamicTops[] = {DynamicTop::two_level, DynamicTop::rebraid,
                                       DynamicTop::rebraid_incremental};

/// Settings of a DynamicSceneAccel with this top and update method, the rest default.
DynamicSceneAccelSettings settings_for(DynamicTop top, UpdateStrategy strategy) {
    DynamicSceneAccelSettings settings;
    settings.top = top;
    settings.update.strategy = strategy;
    return settings;
}

/// Calls body(top, strategy) for every top and update method, each traced by name.
template <class Body>
void for_each_top_and_strategy(Body&& body) {
    for (const DynamicTop top : kDynamicTops)
        for (const UpdateStrategy strategy : kUpdateStrategies) {
            SCOPED_TRACE(std::string(dynamic_top_name(top)) + "+" +
                         std::string(update_strategy_name(strategy)));
            body(top, strategy);
        }
}

std::unique_ptr<AnimatedObject> small_twisting_object() {
    return make_twisting_object({.path_segment_count = 96, .tube_segment_count = 8});
}

Scene small_static_scene() {
    return test::make_overlap_scene(30, 5);
}

TEST(DynamicScene, PoseMovesOnlyTheDynamicMeshes) {
    const auto object = small_twisting_object();
    const Scene static_scene = small_static_scene();
    DynamicScene dynamic(static_scene, *object, {.copy_count = 3});
    ASSERT_EQ(dynamic.scene().meshes.size(), static_scene.meshes.size() + 3);
    ASSERT_EQ(dynamic.dynamic_meshes().size(), 3u);
    const Scene before = dynamic.scene();
    dynamic.pose(0.6f);
    for (std::size_t m = 0; m < before.meshes.size(); ++m) {
        const bool moved = before.meshes[m].positions != dynamic.scene().meshes[m].positions;
        EXPECT_EQ(moved, dynamic.is_dynamic_mesh(MeshId(m))) << "mesh " << m;
    }
    for (std::size_t i = 0; i < static_scene.instances.size(); ++i)
        EXPECT_EQ(dynamic.scene().instances[i].object_to_world.translation,
                  static_scene.instances[i].object_to_world.translation);
}

TEST(DynamicScene, CopiesStandInsideTheStaticScenesFootprint) {
    const auto object = small_twisting_object();
    const Scene static_scene = small_static_scene();
    const DynamicScene dynamic(static_scene, *object, {.copy_count = 4, .seed = 9});
    const BBox3f bounds = static_scene.bounds();
    for (std::size_t i = dynamic.static_instance_count(); i < dynamic.scene().instances.size();
         ++i) {
        const Vec3f centre = dynamic.scene().instance_bounds(InstanceId(i)).center();
        EXPECT_GE(centre.x, bounds.min.x);
        EXPECT_LE(centre.x, bounds.max.x);
        EXPECT_GE(centre.z, bounds.min.z);
        EXPECT_LE(centre.z, bounds.max.z);
    }
}

/// Runs `frames` frames of `dynamic` through `accel` (pose, then update).
template <class Updatable>
void run_frames(DynamicScene& dynamic, Updatable& accel, int frames) {
    for (int frame = 1; frame <= frames; ++frame) {
        dynamic.pose(static_cast<float>(frame) * kTimeStep);
        accel.update();
    }
}

/// Each structure in `accels` answers 10,000 varied rays (test_rays.h) as Embree flat built
/// over the scene as it is now.
void expect_matches_embree_flat(const Scene& scene, std::initializer_list<const Accel*> accels,
                                std::uint64_t seed) {
    const glue::EmbreeFlatAccel reference(scene);
    const std::vector<Ray> rays = test::varied_rays(reference, scene.bounds(), 10000, seed);
    const test::AccelAnswers expected = test::trace_all(reference, rays);
    for (const Accel* accel : accels)
        test::expect_same_answers(scene, rays, expected, test::trace_all(*accel, rays),
                                  test::tolerance_for(scene.bounds()));
}

TEST(DynamicFrames, EveryStrategyAndTopMatchEmbreeFlatOnTheDeformedFrame) {
    const auto object = small_twisting_object();
    for_each_top_and_strategy([&](DynamicTop top, UpdateStrategy strategy) {
        DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 3});
        DynamicSceneAccel accel(dynamic, settings_for(top, strategy));
        run_frames(dynamic, accel, kFrameCount);
        expect_matches_embree_flat(dynamic.scene(), {&accel.accel()}, 3);
        // Refit, rotated or rebuilt object trees under a rebuilt top: every box still
        // holds the deformed triangles below it.
        test::expect_boxes_enclose_geometry(dynamic.scene(), accel.accel(), "after frames");
    });
}

TEST(DynamicFrames, StaticMeshesFromAnotherBuilderMatchEmbreeFlat) {
    // Spatial splits put a triangle in several leaves of a static mesh's tree: fine, as those
    // trees are never refit.
    const auto object = small_twisting_object();
    for (DynamicTop top : {DynamicTop::rebraid, DynamicTop::rebraid_incremental}) {
        SCOPED_TRACE(std::string(dynamic_top_name(top)));
        DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 2});
        DynamicSceneAccelSettings settings = settings_for(top, UpdateStrategy::refit);
        settings.static_builder = glue::embree_object_bvh_builder();
        DynamicSceneAccel accel(dynamic, settings);
        run_frames(dynamic, accel, kFrameCount);
        // The static meshes' trees are Embree's, not the own builder's.
        std::size_t differing = 0;
        for (std::size_t m = 0; m < dynamic.static_mesh_count(); ++m) {
            const ObjectBvh& used = accel.accel().object_bvhs()[m];
            const ObjectBvh own = build_object_bvh(dynamic.scene().meshes[m]);
            differing += used.nodes.size() != own.nodes.size() || used.prim_ids != own.prim_ids;
        }
        EXPECT_GT(differing, 0u);
        expect_matches_embree_flat(dynamic.scene(), {&accel.accel()}, 6);
    }
}

TEST(DynamicFrames, EmbreeMethodsMatchEmbreeFlatBuiltFromScratch) {
    const auto object = small_twisting_object();
    for (glue::EmbreeDynamicMode mode :
         {glue::EmbreeDynamicMode::flat, glue::EmbreeDynamicMode::flat_refit,
          glue::EmbreeDynamicMode::instanced}) {
        SCOPED_TRACE(std::string(glue::embree_dynamic_mode_name(mode)));
        DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 3});
        glue::EmbreeDynamicAccel accel(dynamic, mode);
        run_frames(dynamic, accel, kFrameCount);
        expect_matches_embree_flat(dynamic.scene(), {&accel}, 4);
    }
}

TEST(DynamicFrames, RigidlyMovingGltfInstancesMatchEmbreeFlat) {
    const std::string path = std::string(REBRAID_SHARED_SCENES) + "/motion_capture_rom.glb";
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
    const auto object = load_gltf_animated_object(path);
    ASSERT_FALSE(object->moving_instances().empty());
    DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 2});
    DynamicSceneAccel accel(dynamic, {});
    glue::EmbreeDynamicAccel instanced(dynamic, glue::EmbreeDynamicMode::instanced);
    for (int frame = 1; frame <= kFrameCount; ++frame) {
        dynamic.pose(static_cast<float>(frame) * 0.8f);
        accel.update();
        instanced.update();
    }
    expect_matches_embree_flat(dynamic.scene(), {&accel.accel(), &instanced}, 5);
}

/// Writes a glTF file of two triangles side by side (one animation of two channels): instance 0
/// shrinks to scale 0 and grows back (scale 1, 0, 0, 1 at 0, 1, 2 and 3 s: hidden from 1 to 2 s),
/// instance 1 turns about y, so that something always shows.
std::string write_hiding_object_file(const std::string& name) {
    test::GltfTestFile file;
    const int mesh = test::add_triangle_mesh(file);
    file.add_node({{"mesh", mesh}});
    file.add_node({{"mesh", mesh}, {"translation", {2, 0, 0}}});
    file.add_scene({0, 1});
    test::add_channel_animation(file, 0, "scale", {0, 1, 2, 3},
                                {1, 1, 1, 0, 0, 0, 0, 0, 0, 1, 1, 1}, "VEC3");
    test::add_channel_animation(file, 1, "rotation", {0, 3},
                                {0, 0, 0, 1, 0, std::sin(0.5f), 0, std::cos(0.5f)}, "VEC4");
    // One animation driving both nodes (the animator plays animation 0).
    nlohmann::json& animations = file.json["animations"];
    nlohmann::json channel = animations[1]["channels"][0];
    channel["sampler"] = 1;
    animations[0]["samplers"].push_back(animations[1]["samplers"][0]);
    animations[0]["channels"].push_back(channel);
    animations.erase(1);
    return file.write_glb(name);
}

TEST(DynamicFrames, InstancesHiddenAndShownAgainMatchEmbreeFlat) {
    const auto object = load_gltf_animated_object(write_hiding_object_file("hiding_object.glb"));
    // The hiding instance deforms a mesh of its own (collapsed while hidden): the layout of
    // the posed scene never changes.
    EXPECT_EQ(object->rest_scene().meshes.size(), 2u);
    EXPECT_EQ(object->deformed_meshes(), (std::vector<MeshId>{1}));
    EXPECT_EQ(object->moving_instances(), (std::vector<InstanceId>{0, 1}));
    // Copy 0 plays at t, copy 1 at t + 1.5 s (looped into the 3 s): frames at 0.5, 1.5,
    // 2.5 and 3.5 s hide copy 1, then copy 0, then copy 1 again twice.
    const std::vector<float> times = {0.5f, 1.5f, 2.5f, 3.5f};
    auto hidden_copies = [](const DynamicScene& dynamic) {
        std::string hidden;  // per copy: 1 when its hiding instance is collapsed
        for (MeshId m : dynamic.dynamic_meshes()) {
            const std::vector<Vec3f>& positions = dynamic.scene().meshes[m].positions;
            hidden += std::all_of(positions.begin(), positions.end(),
                                  [&](const Vec3f& p) { return p == positions.front(); })
                          ? '1'
                          : '0';
        }
        return hidden;
    };
    std::vector<std::string> hidden_per_frame;
    for_each_top_and_strategy([&](DynamicTop top, UpdateStrategy strategy) {
        DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 2});
        DynamicSceneAccel accel(dynamic, settings_for(top, strategy));
        hidden_per_frame.clear();
        for (float time : times) {
            SCOPED_TRACE("time " + std::to_string(time));
            dynamic.pose(time);
            accel.update();
            hidden_per_frame.push_back(hidden_copies(dynamic));
            expect_matches_embree_flat(dynamic.scene(), {&accel.accel()}, 7);
            test::expect_boxes_enclose_geometry(dynamic.scene(), accel.accel(), "frame");
        }
    });
    // Each copy is hidden and then shown again (or the other way round).
    EXPECT_EQ(hidden_per_frame, (std::vector<std::string>{"01", "10", "01", "01"}));
    for (glue::EmbreeDynamicMode mode :
         {glue::EmbreeDynamicMode::flat, glue::EmbreeDynamicMode::flat_refit,
          glue::EmbreeDynamicMode::instanced}) {
        SCOPED_TRACE(std::string(glue::embree_dynamic_mode_name(mode)));
        DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 2});
        glue::EmbreeDynamicAccel accel(dynamic, mode);
        for (float time : times) {
            SCOPED_TRACE("time " + std::to_string(time));
            dynamic.pose(time);
            accel.update();
            expect_matches_embree_flat(dynamic.scene(), {&accel}, 8);
        }
    }
}

std::uint64_t structure_hash_after_frames(UpdateStrategy strategy, DynamicTop top,
                                          int thread_count) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                    static_cast<std::size_t>(thread_count));
    const auto object = small_twisting_object();
    DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 3});
    DynamicSceneAccel accel(dynamic, settings_for(top, strategy));
    run_frames(dynamic, accel, kFrameCount);
    return accel.accel().stats().structure_hash.value_or(0);
}

TEST(DynamicFrames, SameStructureOnOneAndTwoThreadsAfterFramesOfEveryStrategy) {
    for_each_top_and_strategy([&](DynamicTop top, UpdateStrategy strategy) {
        const std::uint64_t one = structure_hash_after_frames(strategy, top, 1);
        EXPECT_NE(one, 0u);
        EXPECT_EQ(one, structure_hash_after_frames(strategy, top, 2));
    });
}

TEST(DynamicFrames, RememberedSahEqualsAFullRecomputationAfterFrames) {
    const auto object = small_twisting_object();
    for (const DynamicTop top : kDynamicTops) {
        SCOPED_TRACE(std::string(dynamic_top_name(top)));
        DynamicScene dynamic(small_static_scene(), *object, {.copy_count = 3});
        DynamicSceneAccel accel(dynamic, settings_for(top, UpdateStrategy::refit));
        for (int frame = 1; frame <= kFrameCount; ++frame) {
            dynamic.pose(static_cast<float>(frame) * kTimeStep);
            const DynamicFrameReport report = accel.update();
            std::vector<AffineTransform> transforms;
            for (const Instance& instance : dynamic.scene().instances)
                transforms.push_back(instance.object_to_world);
            const InstancedAccel& structure = accel.accel();
            EXPECT_EQ(report.sah, top_level_sah(structure.top_level(), structure.object_bvhs(),
                                                structure.instance_meshes(), transforms))
                << "frame " << frame;
            // From the second frame on, static items come from the cache: with a top whose
            // static part stays the same, exactly the dynamic instances' items are computed
            // (a full re-braid may open static instances differently from frame to frame).
            if (frame == 1) continue;
            std::size_t dynamic_items = 0;
            for (const TopLevelItem& item : structure.top_level().items)
                dynamic_items += item.instance_id >= dynamic.static_instance_count();
            const std::size_t computed = accel.sah_cache().last_computed_count();
            EXPECT_LT(computed, structure.top_level().items.size()) << "frame " << frame;
            if (top != DynamicTop::rebraid) {
                EXPECT_EQ(computed, dynamic_items) << "frame " << frame;
            }
            EXPECT_GT(accel.sah_cache().remembered_count(), 0u);
        }
    }
}

// ---- rebraid trace --time ----------------------------------------------------------------

std::string shell_quote(const std::string& text) {
    std::string quoted = "'";
    for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

/// Rays aimed at every triangle's centroid of `scene` from off its plane, both sides.
std::vector<Ray> rays_at_triangles(const Scene& scene) {
    std::vector<Ray> rays;
    for (const Instance& instance : scene.instances) {
        const Mesh& mesh = scene.meshes[instance.mesh_id];
        for (PrimId p = 0; p < mesh.triangles.size(); ++p) {
            auto corners = mesh.corners(p);
            for (Vec3f& c : corners) c = instance.object_to_world.transform_point(c);
            const Vec3f centroid = (corners[0] + corners[1] + corners[2]) / 3.0f;
            const Vec3f normal = normalize(cross(corners[1] - corners[0], corners[2] - corners[0]));
            for (float side : {1.0f, -1.0f}) {
                Ray ray;
                ray.org = centroid + normal * (3.0f * side);
                ray.dir = normal * -side;
                rays.push_back(ray);
            }
        }
    }
    return rays;
}

std::vector<std::string> trace_with_cli(const std::string& scene_path, const std::string& rays_path,
                                        const std::string& time, const std::string& out_path) {
    const std::string command = shell_quote(REBRAID_CLI) + " trace " + shell_quote(scene_path) +
                                " " + shell_quote(rays_path) + " --time " + time + " -o " +
                                shell_quote(out_path) + " 2>/dev/null";
    const int status = std::system(command.c_str());
    EXPECT_TRUE(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
    std::ifstream in(out_path);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

TEST(TraceCommand, TimeTracesTheSceneAsAnimatedAtThatTime) {
    const std::string scene_path = test::write_two_joint_skin_file("trace_time_skin.glb", {});
    GltfLoadResult loaded = load_gltf_scene_with_report(scene_path, {.keep_model = true});
    const GltfAnimator animator(loaded);
    Scene posed = loaded.scene;
    animator.apply(0.5f, posed);
    const std::vector<Ray> rays = rays_at_triangles(posed);
    const std::string dir = REBRAID_TEST_TMP;
    const std::string rays_path = dir + "/trace_time_rays.txt";
    {
        std::ofstream out(rays_path);
        write_rays(out, rays);
    }
    const InstancedAccel expected_accel = build_rebraid_accel(posed);
    std::vector<Hit> expected(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) expected[i] = expected_accel.intersect(rays[i]);
    std::ostringstream expected_text;
    write_hits(expected_text, expected);
    std::vector<std::string> expected_lines;
    {
        std::istringstream in(expected_text.str());
        for (std::string line; std::getline(in, line);) expected_lines.push_back(line);
    }
    EXPECT_EQ(trace_with_cli(scene_path, rays_path, "0.5", dir + "/trace_time_hits.txt"),
              expected_lines);
    // The pose matters: at time 0 the joint has not turned, so some answer differs.
    EXPECT_NE(trace_with_cli(scene_path, rays_path, "0", dir + "/trace_time_hits_0.txt"),
              expected_lines);
}

TEST(TraceCommand, TimeWhereAScaleIsZeroTracesTheInstanceHidden) {
    const std::string scene_path = write_hiding_object_file("trace_time_hiding.glb");
    const GltfLoadResult loaded = load_gltf_scene_with_report(scene_path, {.keep_model = true});
    const GltfAnimator animator(loaded);
    Scene shown = loaded.scene;
    animator.apply(0.5f, shown);
    const std::vector<Ray> rays = rays_at_triangles(shown);  // rays 0 and 1 onto instance 0
    const std::string dir = REBRAID_TEST_TMP;
    const std::string rays_path = dir + "/trace_time_hiding_rays.txt";
    {
        std::ofstream out(rays_path);
        write_rays(out, rays);
    }
    // Instance 0 is hidden at 1.5 s (scale 0), shown at 0.5 s; every structure agrees.
    for (const float time : {0.5f, 1.5f}) {
        Scene posed = loaded.scene;
        animator.apply(time, posed);
        const glue::EmbreeFlatAccel reference(posed);
        std::vector<Hit> expected(rays.size());
        for (std::size_t i = 0; i < rays.size(); ++i) expected[i] = reference.intersect(rays[i]);
        EXPECT_EQ(expected[0].is_hit() && expected[0].instance_id == 0, time < 1.0f);
        for (const char* accel :
             {"flat", "twolevel", "rebraid", "embree-flat", "embree-instanced"}) {
            SCOPED_TRACE(std::string(accel) + " at " + std::to_string(time) + " s");
            const std::string out_path = dir + "/trace_time_hiding_" + accel + ".txt";
            const std::vector<std::string> lines = trace_with_cli(
                scene_path, rays_path, std::to_string(time) + " --accel " + accel, out_path);
            ASSERT_EQ(lines.size(), rays.size());
            // Each line: t instID primID, or "inf -1 -1" for a miss.
            for (std::size_t i = 0; i < rays.size(); ++i) {
                std::istringstream line(lines[i]);
                std::string t;
                long long instance = 0, prim = 0;
                line >> t >> instance >> prim;
                const Hit& e = expected[i];
                EXPECT_EQ(instance, e.is_hit() ? (long long)e.instance_id : -1) << "ray " << i;
                EXPECT_EQ(prim, e.is_hit() ? (long long)e.prim_id : -1) << "ray " << i;
                if (e.is_hit()) {
                    EXPECT_NEAR(std::stof(t), e.t, 1e-5f * e.t) << "ray " << i;
                }
            }
        }
    }
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    return bytes.str();
}

/// Renders the two-joint skin file with a fixed camera; returns the exit status.
int render_with_cli(const std::string& scene_path, const std::string& extra,
                    const std::string& image_path) {
    std::string command = shell_quote(REBRAID_CLI);
    command += " render ";
    command += shell_quote(scene_path);
    command += " --mode normals --width 48 --height 32 --look-from 1,0.5,4 --look-at 1,0.5,0 ";
    command += extra;
    command += " -o ";
    command += shell_quote(image_path);
    command += " >/dev/null 2>&1";
    const int status = std::system(command.c_str());
    return (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
}

TEST(RenderCommand, TimeRendersThePoseTheAnimationReachesAtThatTime) {
    const std::string scene_path = test::write_two_joint_skin_file("render_time_skin.glb", {});
    const std::string dir = REBRAID_TEST_TMP;
    ASSERT_EQ(render_with_cli(scene_path, "--time 0.5", dir + "/render_time_half.png"), 0);
    ASSERT_EQ(render_with_cli(scene_path, "--time 0", dir + "/render_time_zero.png"), 0);
    // Frame 1 of an animation stepping 0.5 s is the same pose, posed by the frame loop.
    ASSERT_EQ(
        render_with_cli(scene_path, "--frames 2 --time-step 0.5", dir + "/render_time_frames.png"),
        0);
    const std::string half = read_bytes(dir + "/render_time_half.png");
    ASSERT_FALSE(half.empty());
    EXPECT_EQ(half, read_bytes(dir + "/render_time_frames_0001.png"));
    EXPECT_NE(half, read_bytes(dir + "/render_time_zero.png"));
}

}  // namespace
}  // namespace rebraid
