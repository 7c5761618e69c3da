// EXT_mesh_gpu_instancing, KHR_mesh_quantization positions and hidden (singular) instances:
// small written files for each convention and error, and instanced copies of shared scenes
// traced by Embree against the originals.
#include "rebraid/io/gltf_gpu_instancing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/io/gltf_animation.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/io/gltf_writer.h"
#include "support/gltf_animation_files.h"
#include "support/gltf_test_files.h"
#include "support/hit_comparison.h"
#include "support/own_structures.h"
#include "support/test_rays.h"

namespace rebraid {
namespace {

using test::GltfTestFile;
using test::primitive;

constexpr int kByte = 5120;
constexpr int kShort = 5122;

/// Bytes of `values` (any trivially copyable element type) as a bufferView and accessor.
template <typename T>
int add_values(GltfTestFile& file, const std::vector<T>& values, int component_type,
               std::uint64_t count, const std::string& type, bool normalized = false) {
    const int view = file.add_view(values.data(), values.size() * sizeof(T));
    const int accessor = file.add_accessor(view, component_type, count, type);
    if (normalized) file.json["accessors"][accessor]["normalized"] = true;
    return accessor;
}

/// One triangle mesh (corners (0,0,0), (1,0,0), (0,1,0)).
GltfTestFile triangle_file() {
    GltfTestFile file;
    file.add_mesh({primitive(file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))});
    return file;
}

nlohmann::json instancing(const nlohmann::json& attributes) {
    return {{"EXT_mesh_gpu_instancing", {{"attributes", attributes}}}};
}

/// Three instances: translations (10,0,0), (0,10,0), (0,0,10); rotations identity, 90 degrees
/// about +z (as normalized shorts), identity; scales 1, 2, 3.
GltfTestFile three_instances_file() {
    GltfTestFile file = triangle_file();
    // Accessors 1 (TRANSLATION), 2 (ROTATION) and 3 (SCALE), after the positions' 0.
    add_values<float>(file, {10, 0, 0, 0, 10, 0, 0, 0, 10}, test::kFloat, 3, "VEC3");
    const std::int16_t h = std::int16_t(std::lround(std::sqrt(0.5) * 32767));
    add_values<std::int16_t>(file, {0, 0, 0, 32767, 0, 0, h, h, 0, 0, 0, 32767}, kShort, 3, "VEC4",
                             true);
    add_values<float>(file, {1, 1, 1, 2, 2, 2, 3, 3, 3}, test::kFloat, 3, "VEC3");
    return file;
}

void expect_near(Vec3f actual, Vec3f expected, float tolerance = 1e-4f) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

void expect_load_error(const std::string& path, const std::string& phrase) {
    try {
        load_gltf_scene(path);
        ADD_FAILURE() << "no error loading " << path << " (expected '" << phrase << "')";
    } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find(phrase), std::string::npos) << error.what();
    }
}

// ---- EXT_mesh_gpu_instancing -------------------------------------------------------------------

/// Node 0: plain instance; node 1 (translated by (0,0,100)): instanced with accessors 1-3
/// and child node 2 (plain). Depth-first: node 0, node 1's three elements, node 2.
GltfTestFile numbering_file(bool list_as_required) {
    GltfTestFile file = three_instances_file();
    file.add_node({{"mesh", 0}});
    file.add_node(
        {{"mesh", 0},
         {"translation", {0, 0, 100}},
         {"children", {2}},
         {"extensions", instancing({{"TRANSLATION", 1}, {"ROTATION", 2}, {"SCALE", 3}})}});
    file.add_node({{"mesh", 0}, {"translation", {5, 5, 5}}});
    file.add_scene({0, 1});
    file.json["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
    if (list_as_required) file.json["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
    return file;
}

TEST(GltfGpuInstancing, ElementsTakeTheirNodesPlaceDepthFirst) {
    for (bool required : {true, false}) {
        SCOPED_TRACE(required ? "listed as required" : "only used");
        const GltfLoadResult loaded = load_gltf_scene_with_report(
            numbering_file(required).write_glb(required ? "gpu_req.glb" : "gpu_used.glb"));
        const Scene& scene = loaded.scene;
        ASSERT_EQ(scene.instances.size(), 5u);  // the instanced node's mesh only via elements
        EXPECT_EQ(loaded.report.instance_node_ids, (std::vector<std::uint32_t>{0, 1, 1, 1, 2}));
        EXPECT_EQ(loaded.report.instance_gpu_elements,
                  (std::vector<std::uint32_t>{kNotGpuInstanced, 0, 1, 2, kNotGpuInstanced}));
        // World = node (translate (0,0,100)) * T * R * S of the element; corner (1,0,0):
        expect_near(scene.instances[1].object_to_world.transform_point({1, 0, 0}), {11, 0, 100});
        // element 1: scale 2 -> (2,0,0), 90 degrees about z -> (0,2,0), + (0,10,0) + node.
        expect_near(scene.instances[2].object_to_world.transform_point({1, 0, 0}), {0, 12, 100});
        expect_near(scene.instances[3].object_to_world.transform_point({1, 0, 0}), {3, 0, 110});
        // The child of the instanced node follows the node's own transform only.
        expect_near(scene.instances[4].object_to_world.transform_point({0, 0, 0}), {5, 5, 105});
    }
}

TEST(GltfGpuInstancing, MissingAttributesAreTheIdentity) {
    GltfTestFile file = triangle_file();
    const int translation = add_values<float>(file, {1, 2, 3, 4, 5, 6}, test::kFloat, 2, "VEC3");
    file.add_node({{"mesh", 0}, {"extensions", instancing({{"TRANSLATION", translation}})}});
    file.add_scene({0});
    const Scene scene = load_gltf_scene(file.write_glb("gpu_translation_only.glb"));
    ASSERT_EQ(scene.instances.size(), 2u);
    expect_near(scene.instances[1].object_to_world.transform_point({1, 1, 1}), {5, 6, 7});
    expect_near(scene.instances[1].object_to_world.col_x, {1, 0, 0}, 0);
}

TEST(GltfGpuInstancing, MovesWithItsAnimatedNode) {
    GltfTestFile file = three_instances_file();
    file.add_node(
        {{"mesh", 0},
         {"extensions", instancing({{"TRANSLATION", 1}, {"ROTATION", 2}, {"SCALE", 3}})}});
    file.add_scene({0});
    // Node 0 moves from (0,0,0) at t = 0 to (0,0,8) at t = 1.
    const int times = add_values<float>(file, {0, 1}, test::kFloat, 2, "SCALAR");
    const int moves = add_values<float>(file, {0, 0, 0, 0, 0, 8}, test::kFloat, 2, "VEC3");
    file.json["animations"] = {
        {{"samplers", {{{"input", times}, {"output", moves}, {"interpolation", "LINEAR"}}}},
         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "translation"}}}}}}}};
    const GltfLoadResult loaded =
        load_gltf_scene_with_report(file.write_glb("gpu_animated.glb"), {.keep_model = true});
    const GltfAnimator animator(loaded);
    Scene scene = loaded.scene;
    animator.apply(0.5f, scene);
    ASSERT_EQ(animator.moving_instances().size(), 3u);
    expect_near(scene.instances[0].object_to_world.transform_point({1, 0, 0}), {11, 0, 4});
    expect_near(scene.instances[1].object_to_world.transform_point({1, 0, 0}), {0, 12, 4});
    expect_near(scene.instances[2].object_to_world.transform_point({1, 0, 0}), {3, 0, 14});
}

TEST(GltfGpuInstancingErrors, EachBadInputHasItsMessage) {
    auto broken = [](const std::string& name, auto&& change) {
        GltfTestFile file = numbering_file(true);
        change(file);
        return file.write_glb(name);
    };
    auto ext = [](GltfTestFile& f) -> nlohmann::json& {
        return f.json["nodes"][1]["extensions"]["EXT_mesh_gpu_instancing"];
    };
    expect_load_error(
        broken("gpu_counts.glb", [&](GltfTestFile& f) { f.json["accessors"][3]["count"] = 2; }),
        "SCALE has 2 elements, the other attributes 3");
    expect_load_error(broken("gpu_zero.glb",
                             [&](GltfTestFile& f) {
                                 for (int a : {1, 2, 3}) f.json["accessors"][a]["count"] = 0;
                             }),
                      "count of zero");
    expect_load_error(broken("gpu_type.glb",
                             [&](GltfTestFile& f) {
                                 f.json["accessors"][1]["componentType"] = test::kUnsignedShort;
                             }),
                      "TRANSLATION must be a float VEC3 accessor");
    expect_load_error(
        broken("gpu_unnormalized.glb",
               [&](GltfTestFile& f) { f.json["accessors"][2]["normalized"] = false; }),
        "ROTATION must be a float or normalized byte or short VEC4 accessor");
    expect_load_error(
        broken("gpu_past.glb", [&](GltfTestFile& f) { f.json["accessors"][1]["count"] = 300; }),
        "runs past the end");
    expect_load_error(
        broken("gpu_no_mesh.glb", [&](GltfTestFile& f) { f.json["nodes"][1].erase("mesh"); }),
        "no mesh to instance");
    // tinygltf drops an empty object: no attributes at all reads as a missing object.
    expect_load_error(
        broken("gpu_no_attributes.glb",
               [&](GltfTestFile& f) { ext(f)["attributes"] = nlohmann::json::object(); }),
        "needs an 'attributes' object");
    expect_load_error(broken("gpu_only_custom.glb",
                             [&](GltfTestFile& f) {
                                 ext(f)["attributes"] = {{"_ID", 1}};
                             }),
                      "needs a TRANSLATION, ROTATION or SCALE attribute");
    expect_load_error(
        broken("gpu_bad_index.glb", [&](GltfTestFile& f) { ext(f)["attributes"]["SCALE"] = 99; }),
        "references accessor 99");
    expect_load_error(
        broken("gpu_unknown.glb", [&](GltfTestFile& f) { ext(f)["attributes"]["COLOR"] = 1; }),
        "unknown attribute 'COLOR'");
}

TEST(GltfGpuInstancingErrors, NonUnitOrNanRotation) {
    for (const float w : {0.5f, std::numeric_limits<float>::quiet_NaN(), 0.0f}) {
        GltfTestFile file = triangle_file();
        const int rotation =
            add_values<float>(file, {0, 0, 0, 1, 0, 0, 0, w}, test::kFloat, 2, "VEC4");
        file.add_node({{"mesh", 0}, {"extensions", instancing({{"ROTATION", rotation}})}});
        file.add_scene({0});
        expect_load_error(file.write_glb("gpu_rotation.glb"),
                          "ROTATION of instance 1 is not a unit quaternion");
    }
    GltfTestFile file = triangle_file();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const int translation = add_values<float>(file, {0, 0, 0, nan, 0, 0}, test::kFloat, 2, "VEC3");
    file.add_node({{"mesh", 0}, {"extensions", instancing({{"TRANSLATION", translation}})}});
    file.add_scene({0});
    expect_load_error(file.write_glb("gpu_nan.glb"), "TRANSLATION of instance 1 is not finite");
}

TEST(GltfGpuInstancingErrors, InstanceLimit) {
    try {
        load_gltf_scene(numbering_file(true).write_glb("gpu_limit.glb"), {.max_instances = 3});
        ADD_FAILURE() << "no error";
    } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find("max_instances = 3"), std::string::npos);
    }
}

TEST(GltfGpuInstancing, WriterRunsKeepOrderMirrorsAndShears) {
    Scene scene;
    scene.meshes.push_back({"tri", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}});
    const AffineTransform turned =
        AffineTransform::translate({1, 2, 3}) * AffineTransform::rotate({1, 1, 0}, 0.7f);
    const AffineTransform mirrored =
        AffineTransform::rotate({0, 0, 1}, 2.0f) * AffineTransform::scale({-1, 2, 0.5f});
    const AffineTransform sheared{{1, 0, 0}, {0.5f, 1, 0}, {0, 0, 1}, {4, 0, 0}};
    for (const AffineTransform& t : {turned, mirrored, sheared, turned, mirrored, turned})
        scene.instances.push_back({0, t});
    const std::string path = test::scratch_path("writer_runs.gltf");
    write_gltf_scene(scene, path, {.gpu_instancing = true});
    const GltfLoadResult loaded = load_gltf_scene_with_report(path, {.keep_model = true});
    // Nodes: instanced (turned, mirrored), matrix (sheared), instanced (the last three).
    ASSERT_EQ(loaded.model->nodes.size(), 3u);
    EXPECT_FALSE(loaded.model->nodes[1].matrix.empty());
    EXPECT_EQ(loaded.report.instance_gpu_elements,
              (std::vector<std::uint32_t>{0, 1, kNotGpuInstanced, 0, 1, 2}));
    ASSERT_EQ(loaded.scene.instances.size(), scene.instances.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        const AffineTransform& a = scene.instances[i].object_to_world;
        const AffineTransform& b = loaded.scene.instances[i].object_to_world;
        expect_near(b.col_x, a.col_x, 1e-6f);
        expect_near(b.col_y, a.col_y, 1e-6f);
        expect_near(b.col_z, a.col_z, 1e-6f);
        expect_near(b.translation, a.translation, 0);
    }
}

// ---- Hidden (singular) instances --------------------------------------------------------------

/// Hidden instances 0, 2 and 4 (a zero node scale, a zero element SCALE, a zero y scale)
/// around shown instances 1 and 3 of one mesh (mesh 1 is the loader's hidden mesh).
GltfLoadResult load_hidden_instances_file() {
    GltfTestFile file = triangle_file();
    const int scale = add_values<float>(file, {1, 1, 1, 0, 0, 0, 2, 2, 2}, test::kFloat, 3, "VEC3");
    file.add_node({{"mesh", 0}, {"scale", {0, 0, 0}}, {"translation", {0, 0, 5}}});
    file.add_node({{"mesh", 0}, {"extensions", instancing({{"SCALE", scale}})}});
    file.add_node({{"mesh", 0}, {"scale", {1, 0, 1}}, {"translation", {0, 0, 5}}});
    file.add_scene({0, 1, 2});
    return load_gltf_scene_with_report(file.write_glb("hidden.glb"));
}

TEST(GltfHiddenInstances, ZeroScaleInstancesKeepTheirNumberAndAreNeverHit) {
    const GltfLoadResult loaded = load_hidden_instances_file();
    const Scene& scene = loaded.scene;
    ASSERT_EQ(scene.instances.size(), 5u);
    EXPECT_EQ(loaded.report.hidden_instances, (std::vector<std::uint32_t>{0, 2, 4}));
    EXPECT_EQ(loaded.report.instance_node_ids, (std::vector<std::uint32_t>{0, 1, 1, 1, 2}));
    ASSERT_EQ(loaded.report.hidden_mesh, 1u);
    ASSERT_EQ(scene.meshes.size(), 2u);
    EXPECT_TRUE(scene.meshes[1].triangles.empty());
    for (std::uint32_t i : loaded.report.hidden_instances) {
        EXPECT_EQ(scene.instances[i].mesh_id, 1u);
        EXPECT_TRUE(scene.instances[i].object_to_world == AffineTransform::identity());
    }
    EXPECT_EQ(scene.instances[3].mesh_id, 0u);
    // Embree on the loaded scene: nothing at z = 5 (the hidden nodes); instance 1 at z = 0.
    const glue::EmbreeFlatAccel embree(scene);
    EXPECT_FALSE(embree.intersect({{0.2f, 0.2f, 10}, 0, {0, 0, -1}, 7}).is_hit());
    const Hit shown = embree.intersect({{0.2f, 0.2f, 10}, 0, {0, 0, -1}, 100});
    ASSERT_TRUE(shown.is_hit());
    EXPECT_FLOAT_EQ(shown.t, 10);
    EXPECT_TRUE(shown.instance_id == 1 || shown.instance_id == 3);  // coplanar, both at z = 0
}

TEST(GltfHiddenInstances, HiddenAtRestShowsWhereItsAnimationScalesItUp) {
    GltfTestFile file = triangle_file();
    file.add_node({{"mesh", 0}, {"scale", {0, 0, 0}}});
    file.add_node({{"mesh", 0}});
    file.add_scene({0, 1});
    // Node 0 grows from scale 0 to 1, node 1 moves along z.
    const int times = add_values<float>(file, {0, 1}, test::kFloat, 2, "SCALAR");
    const int scales = add_values<float>(file, {0, 0, 0, 1, 1, 1}, test::kFloat, 2, "VEC3");
    const int moves = add_values<float>(file, {0, 0, 0, 0, 0, 8}, test::kFloat, 2, "VEC3");
    file.json["animations"] = {
        {{"samplers",
          {{{"input", times}, {"output", scales}}, {{"input", times}, {"output", moves}}}},
         {"channels",
          {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "scale"}}}},
           {{"sampler", 1}, {"target", {{"node", 1}, {"path", "translation"}}}}}}}};
    const GltfLoadResult loaded =
        load_gltf_scene_with_report(file.write_glb("hidden_animated.glb"), {.keep_model = true});
    EXPECT_EQ(loaded.report.hidden_instances, (std::vector<std::uint32_t>{0}));
    // A ray up through node 0's triangle (at z = 0 from scale 0.5 on), then node 1's (at
    // z = 8 time): it meets node 0 first wherever that is shown, else node 1.
    const Ray onto_node_0{{0.1f, 0.1f, -10}, 0, {0, 0, 1}};
    for (const GltfHiddenPose mode : {GltfHiddenPose::empty_mesh, GltfHiddenPose::collapsed_mesh}) {
        SCOPED_TRACE(mode == GltfHiddenPose::empty_mesh ? "empty mesh" : "collapsed mesh");
        const GltfAnimator animator(loaded, {.hidden_pose = mode});
        EXPECT_EQ(animator.hideable_instances(), (std::vector<InstanceId>{0}));
        Scene scene = loaded.scene;  // posed again and again, as a frame loop does
        for (const float time : {0.0f, 0.5f, 1.0f, 0.0f}) {
            SCOPED_TRACE("time " + std::to_string(time));
            animator.apply(time, scene);
            ASSERT_NO_THROW(scene.validate());
            expect_near(scene.instances[1].object_to_world.translation, {0, 0, 8 * time});
            const bool is_hidden = time == 0.0f;
            if (mode == GltfHiddenPose::empty_mesh) {
                EXPECT_EQ(scene.instances[0].mesh_id, is_hidden ? loaded.report.hidden_mesh : 0u);
            }
            if (!is_hidden) expect_near(scene.instances[0].object_to_world.col_x, {time, 0, 0});
            const InstanceId first_met = is_hidden ? 1 : 0;
            const glue::EmbreeFlatAccel embree(scene);
            const Hit hit = embree.intersect(onto_node_0);
            ASSERT_TRUE(hit.is_hit());
            EXPECT_EQ(hit.instance_id, first_met);
            EXPECT_FLOAT_EQ(hit.t, 10);
            for (const auto& [name, accel] : test::own_structures(scene, 4.0f))
                EXPECT_EQ(accel->intersect(onto_node_0).instance_id, first_met) << name;
        }
    }
}

/// Moves the channels of every animation of `file` into animation 0, so that they play
/// together (the animator plays animation 0 by default).
void merge_animations(GltfTestFile& file) {
    nlohmann::json& animations = file.json["animations"];
    for (std::size_t a = 1; a < animations.size(); ++a) {
        const std::size_t offset = animations[0]["samplers"].size();
        for (const nlohmann::json& sampler : animations[a]["samplers"])
            animations[0]["samplers"].push_back(sampler);
        for (nlohmann::json channel : animations[a]["channels"]) {
            channel["sampler"] = channel["sampler"].get<std::size_t>() + offset;
            animations[0]["channels"].push_back(channel);
        }
    }
    animations = nlohmann::json::array({animations[0]});
}

/// A file whose instances an animated scale hides and shows (node 0 has the triangle):
/// instance 0 (node 0, at z = 5) shrinks from scale 1 at 0 s to 0 at 1 s and stays hidden;
/// instances 1 and 2 (two EXT_mesh_gpu_instancing elements, at (0,0,0) and (0,2,0), of node
/// 2 below node 1 at (3,0,0)) follow node 1's scale 1 -> 0 -> 1 over 0, 1.5 and 3 s;
/// instance 3 (node 3, at (-3,0,0)) never moves.
GltfTestFile hiding_animation_file() {
    GltfTestFile file = triangle_file();
    const int elements = add_values<float>(file, {0, 0, 0, 0, 2, 0}, test::kFloat, 2, "VEC3");
    file.add_node({{"mesh", 0}, {"translation", {0, 0, 5}}});
    file.add_node({{"translation", {3, 0, 0}}, {"children", {2}}});
    file.add_node({{"mesh", 0}, {"extensions", instancing({{"TRANSLATION", elements}})}});
    file.add_node({{"mesh", 0}, {"translation", {-3, 0, 0}}});
    file.add_scene({0, 1, 3});
    test::add_channel_animation(file, 0, "scale", {0, 1}, {1, 1, 1, 0, 0, 0}, "VEC3");
    test::add_channel_animation(file, 1, "scale", {0, 1.5f, 3}, {1, 1, 1, 0, 0, 0, 1, 1, 1},
                                "VEC3");
    merge_animations(file);
    return file;
}

/// Rays straight down onto each of hiding_animation_file()'s instances, as placed at `time`
/// (`scale_1`: node 1's scale then), well inside its triangle while it is shown.
std::vector<Ray> rays_onto_hiding_instances(float scale_1) {
    const float offset = 0.02f;
    return {{{offset, offset, 10}, 0, {0, 0, -1}},
            {{3 + offset, offset, 10}, 0, {0, 0, -1}},
            {{3 + offset, 2 * scale_1 + offset, 10}, 0, {0, 0, -1}},
            {{-3 + 0.1f, 0.1f, 10}, 0, {0, 0, -1}}};
}

/// Every structure over `scene` (flat, twolevel, rebraid, Embree's instanced) answers varied
/// rays as Embree flat does, never hits an instance in `hidden`, and answers `aimed[i]` with
/// instance i unless i is hidden (then with a miss).
void expect_hidden_instances_never_hit(const Scene& scene, const std::vector<InstanceId>& hidden,
                                       const std::vector<Ray>& aimed) {
    const glue::EmbreeFlatAccel reference(scene);
    std::vector<Ray> rays = test::varied_rays(reference, scene.bounds(), 3000, 11);
    // Rays down and up through a grid over every place an instance can be: the small
    // triangles get hit often.
    for (int x = 0; x < 32; ++x)
        for (int y = 0; y < 16; ++y) {
            const Vec3f org{-3.5f + 0.25f * float(x) + 0.01f, -0.5f + 0.25f * float(y) + 0.01f, 10};
            rays.push_back({org, 0, {0, 0, -1}});
            rays.push_back({{org.x, org.y, -5}, 0, {0, 0, 1}});
        }
    rays.insert(rays.end(), aimed.begin(), aimed.end());
    const test::AccelAnswers expected = test::trace_all(reference, rays);
    test::NamedAccels structures = test::own_structures(scene, 4.0f);
    structures.emplace_back("embree-instanced",
                            std::make_unique<glue::EmbreeInstancedAccel>(scene));
    structures.emplace_back("embree-flat", std::make_unique<glue::EmbreeFlatAccel>(scene));
    for (const auto& [name, accel] : structures) {
        SCOPED_TRACE(name);
        const test::AccelAnswers answers = test::trace_all(*accel, rays);
        test::Tolerance tolerance = test::tolerance_for(scene.bounds());
        tolerance.min_hit_fraction = 0.005;  // a few small triangles in the grid
        test::expect_same_answers(scene, rays, expected, answers, tolerance);
        for (const Hit& hit : answers.hits)
            EXPECT_FALSE(hit.is_hit() &&
                         std::count(hidden.begin(), hidden.end(), hit.instance_id) > 0)
                << "hidden instance " << hit.instance_id << " was hit";
        const std::size_t first_aimed = rays.size() - aimed.size();
        for (InstanceId i = 0; i < aimed.size(); ++i) {
            const Hit& hit = answers.hits[first_aimed + i];
            if (std::count(hidden.begin(), hidden.end(), i) > 0) {
                EXPECT_FALSE(hit.is_hit()) << "ray onto hidden instance " << i;
            } else {
                EXPECT_TRUE(hit.is_hit() && hit.instance_id == i) << "ray onto instance " << i;
            }
        }
    }
}

TEST(GltfHiddenInstances, ScaleAnimatedToZeroHidesTheInstanceInThosePosesOnly) {
    const GltfLoadResult loaded =
        test::load_animated(hiding_animation_file().write_glb("hiding_animation.glb"));
    ASSERT_EQ(loaded.scene.instances.size(), 4u);
    EXPECT_TRUE(loaded.report.hidden_instances.empty());
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.hideable_instances(), (std::vector<InstanceId>{0, 1, 2}));
    // No hidden mesh in the file: the prepared layout appends one.
    ASSERT_EQ(animator.hidden_mesh(), 1u);
    ASSERT_EQ(animator.mesh_count(), 2u);
    struct Pose {
        float time;
        float scale_1;  // node 1's scale
        std::vector<InstanceId> hidden;
    };
    // Shown, then 0 hidden, then 0, 1 and 2 hidden, then 1 and 2 shown again.
    const std::vector<Pose> poses = {
        {0.5f, 2 / 3.0f, {}}, {1.0f, 1 / 3.0f, {0}}, {1.5f, 0, {0, 1, 2}}, {2.5f, 2 / 3.0f, {0}}};
    Scene scene = loaded.scene;  // posed again and again, as a frame loop does
    for (const Pose& pose : poses) {
        SCOPED_TRACE("time " + std::to_string(pose.time));
        animator.apply(pose.time, scene);
        ASSERT_NO_THROW(scene.validate());
        ASSERT_EQ(scene.instances.size(), 4u);
        ASSERT_EQ(scene.meshes.size(), 2u);
        EXPECT_TRUE(scene.meshes[1].triangles.empty());
        for (InstanceId i = 0; i < 4; ++i) {
            const bool is_hidden = std::count(pose.hidden.begin(), pose.hidden.end(), i) > 0;
            EXPECT_EQ(scene.instances[i].mesh_id, is_hidden ? 1u : 0u) << "instance " << i;
            if (is_hidden) {
                EXPECT_TRUE(scene.instances[i].object_to_world == AffineTransform::identity());
            }
        }
        expect_hidden_instances_never_hit(scene, pose.hidden,
                                          rays_onto_hiding_instances(pose.scale_1));
        // The same pose from a freshly loaded scene.
        Scene fresh = loaded.scene;
        animator.apply(pose.time, fresh);
        for (InstanceId i = 0; i < 4; ++i) {
            EXPECT_EQ(fresh.instances[i].mesh_id, scene.instances[i].mesh_id);
            EXPECT_TRUE(fresh.instances[i].object_to_world == scene.instances[i].object_to_world);
        }
    }
}

TEST(GltfHiddenInstances, ScaleCrossingZeroHidesOnlyAtTheCrossing) {
    // x scale 1 -> -1 over 2 s: shown, hidden at 1 s (scale 0), then shown mirrored. A
    // second instance stands still beside it.
    GltfTestFile file = triangle_file();
    file.add_node({{"mesh", 0}});
    file.add_node({{"mesh", 0}, {"translation", {3, 0, 0}}});
    file.add_scene({0, 1});
    test::add_channel_animation(file, 0, "scale", {0, 2}, {1, 1, 1, -1, 1, 1}, "VEC3");
    const GltfLoadResult loaded = test::load_animated(file.write_glb("hiding_crossing.glb"));
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.hideable_instances(), (std::vector<InstanceId>{0}));
    const Ray shown{{0.1f, 0.1f, 10}, 0, {0, 0, -1}};
    const Ray mirrored{{-0.1f, 0.1f, 10}, 0, {0, 0, -1}};
    Scene scene = loaded.scene;
    for (float time : {0.5f, 1.0f, 1.5f}) {
        SCOPED_TRACE("time " + std::to_string(time));
        animator.apply(time, scene);
        ASSERT_NO_THROW(scene.validate());
        const bool is_hidden = time == 1.0f;
        EXPECT_EQ(scene.instances[0].mesh_id, is_hidden ? animator.hidden_mesh() : 0u);
        expect_hidden_instances_never_hit(
            scene, is_hidden ? std::vector<InstanceId>{0} : std::vector<InstanceId>{},
            {time < 1.0f ? shown : mirrored});
    }
}

TEST(GltfHiddenInstances, OnlyScalesThatMayReachZeroMakeAnInstanceHideable) {
    struct Case {
        const char* name;
        std::vector<float> times, values;  // x scale keys (y, z stay 1); values with tangents
        const char* interpolation;
        bool is_hideable;
    };
    const std::vector<Case> cases = {
        {"growing", {0, 1}, {1, 2}, "LINEAR", false},
        {"step to zero", {0, 1}, {1, 0}, "STEP", true},
        {"tiny", {0, 1}, {1, 1e-31f}, "LINEAR", true},
        // CUBICSPLINE keys (in-tangent, value, out-tangent): positive values; a steep
        // tangent dips the curve below zero between them, a gentle one does not.
        {"gentle spline", {0, 1}, {0, 1, 0.5f, 0, 1, 0}, "CUBICSPLINE", false},
        {"steep spline", {0, 1}, {0, 1, -20, 0, 1, 0}, "CUBICSPLINE", true},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        GltfTestFile file = triangle_file();
        file.add_node({{"mesh", 0}});
        file.add_node({{"mesh", 0}, {"translation", {5, 0, 0}}});
        file.add_scene({0, 1});
        std::vector<float> values;
        for (float x : c.values) values.insert(values.end(), {x, 1, 1});
        test::add_channel_animation(file, 0, "scale", c.times, values, "VEC3", c.interpolation);
        const GltfLoadResult loaded = test::load_animated(file.write_glb("hideable.glb"));
        const GltfAnimator animator(loaded);
        EXPECT_EQ(animator.hideable_instances().size(), c.is_hideable ? 1u : 0u);
        // An animation that cannot hide anything keeps the loader's layout.
        EXPECT_EQ(animator.mesh_count(), c.is_hideable ? 2u : 1u);
        EXPECT_EQ(animator.hidden_mesh(), c.is_hideable ? 1u : kNoHiddenMesh);
        // Sampled densely, a singular pose happens only to a hideable instance.
        Scene scene = loaded.scene;
        for (int step = 0; step <= 200; ++step) {
            ASSERT_NO_THROW(animator.apply(float(step) / 200, scene));
            ASSERT_NO_THROW(scene.validate());
        }
    }
}

TEST(GltfHiddenInstances, CollapsedHiddenPosesKeepTheLayout) {
    const GltfLoadResult loaded =
        test::load_animated(hiding_animation_file().write_glb("hiding_collapsed.glb"));
    const GltfAnimator animator(loaded, {.hidden_pose = GltfHiddenPose::collapsed_mesh});
    EXPECT_EQ(animator.hideable_instances(), (std::vector<InstanceId>{0, 1, 2}));
    // Each hideable instance deforms a mesh of its own; instance 3 keeps the loaded mesh.
    EXPECT_EQ(animator.mesh_ids(), (std::vector<MeshId>{1, 2, 3, 0}));
    EXPECT_EQ(animator.deformed_meshes(), (std::vector<MeshId>{1, 2, 3}));
    EXPECT_EQ(animator.hidden_mesh(), kNoHiddenMesh);
    Scene scene = loaded.scene;
    for (const float time : {0.5f, 1.5f, 2.5f, 0.5f}) {
        SCOPED_TRACE("time " + std::to_string(time));
        animator.apply(time, scene);
        ASSERT_NO_THROW(scene.validate());
        ASSERT_EQ(scene.meshes.size(), 4u);
        const float scale_1 = time == 1.5f ? 0.0f : 2 / 3.0f;
        std::vector<InstanceId> hidden;
        if (time > 1.0f) hidden.push_back(0);
        if (time == 1.5f) hidden.insert(hidden.end(), {1, 2});
        for (InstanceId i = 0; i < 4; ++i) {
            EXPECT_EQ(scene.instances[i].mesh_id, animator.mesh_ids()[i]);
            const std::vector<Vec3f>& positions = scene.meshes[animator.mesh_ids()[i]].positions;
            const bool is_collapsed =
                std::all_of(positions.begin(), positions.end(),
                            [&](const Vec3f& p) { return p == positions.front(); });
            EXPECT_EQ(is_collapsed, std::count(hidden.begin(), hidden.end(), i) > 0)
                << "instance " << i;
        }
        expect_hidden_instances_never_hit(scene, hidden, rays_onto_hiding_instances(scale_1));
    }
}

// ---- Writing hidden instances ------------------------------------------------------------------

/// Loads `path` and checks it holds `original`'s instances in order: the same hidden ones (an
/// identity instance of the hidden mesh), the others on the same mesh at (nearly, after a
/// float T, R, S) the same transform; and that Embree answers rays on both alike.
GltfLoadResult expect_round_trip(const GltfLoadResult& original, const std::string& path) {
    const GltfLoadResult loaded = load_gltf_scene_with_report(path, {.keep_model = true});
    const Scene& a = original.scene;
    const Scene& b = loaded.scene;
    EXPECT_EQ(loaded.report.hidden_instances, original.report.hidden_instances);
    EXPECT_EQ(loaded.report.hidden_mesh, original.report.hidden_mesh);
    EXPECT_EQ(b.meshes.size(), a.meshes.size());
    EXPECT_TRUE(b.meshes.at(loaded.report.hidden_mesh).triangles.empty());
    EXPECT_NO_THROW(b.validate());
    if (b.instances.size() != a.instances.size()) {
        ADD_FAILURE() << b.instances.size() << " instances, expected " << a.instances.size();
        return loaded;
    }
    for (std::size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_EQ(b.instances[i].mesh_id, a.instances[i].mesh_id) << "instance " << i;
        const AffineTransform& ta = a.instances[i].object_to_world;
        const AffineTransform& tb = b.instances[i].object_to_world;
        expect_near(tb.col_x, ta.col_x, 1e-6f);
        expect_near(tb.col_y, ta.col_y, 1e-6f);
        expect_near(tb.col_z, ta.col_z, 1e-6f);
        expect_near(tb.translation, ta.translation, 0);
    }
    const glue::EmbreeFlatAccel reference(a);
    const std::vector<Ray> rays = test::varied_rays(reference, a.bounds(), 2000, 5);
    test::expect_same_answers(a, rays, test::trace_all(reference, rays),
                              test::trace_all(glue::EmbreeFlatAccel(b), rays),
                              test::tolerance_for(a.bounds()));
    return loaded;
}

TEST(GltfHiddenInstances, WrittenAsZeroScaleNodesTheyLoadBackHidden) {
    const GltfLoadResult original = load_hidden_instances_file();
    ASSERT_EQ(original.report.hidden_instances, (std::vector<std::uint32_t>{0, 2, 4}));
    for (const char* name : {"hidden_nodes.glb", "hidden_nodes.gltf"}) {
        SCOPED_TRACE(name);
        const std::string path = test::scratch_path(name);
        write_gltf_scene(original.scene, path);
        const GltfLoadResult loaded = expect_round_trip(original, path);
        // One node per instance; the hidden ones have a zero scale and the triangle mesh.
        ASSERT_EQ(loaded.model->nodes.size(), 5u);
        EXPECT_EQ(loaded.model->meshes.size(), 1u);
        for (int n : {0, 2, 4}) {
            EXPECT_EQ(loaded.model->nodes[n].scale, (std::vector<double>{0, 0, 0}));
            EXPECT_EQ(loaded.model->nodes[n].mesh, 0);
        }
    }
}

TEST(GltfHiddenInstances, WrittenAsZeroScaleElementsTheyLoadBackHidden) {
    const GltfLoadResult original = load_hidden_instances_file();
    for (const char* name : {"hidden_elements.glb", "hidden_elements.gltf"}) {
        SCOPED_TRACE(name);
        const std::string path = test::scratch_path(name);
        write_gltf_scene(original.scene, path, {.gpu_instancing = true});
        const GltfLoadResult loaded = expect_round_trip(original, path);
        // The hidden instances join the run of the shown ones: one node, five elements.
        ASSERT_EQ(loaded.model->nodes.size(), 1u);
        EXPECT_EQ(loaded.report.instance_gpu_elements, (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
    }
    // Instances of another mesh end a run (hidden instances join the run before); a run of
    // one instance is a node of its own.
    Scene scene = original.scene;
    scene.meshes.insert(scene.meshes.begin() + 1, scene.meshes[0]);  // mesh 1: another triangle
    scene.meshes[1].name = "second";
    for (Instance& instance : scene.instances)
        if (instance.mesh_id == 1) instance.mesh_id = 2;  // the hidden mesh, still last
    scene.instances[3].mesh_id = 1;
    scene.instances.pop_back();
    const std::string path = test::scratch_path("hidden_two_meshes.glb");
    write_gltf_scene(scene, path, {.gpu_instancing = true});
    const GltfLoadResult loaded = load_gltf_scene_with_report(path, {.keep_model = true});
    EXPECT_EQ(loaded.report.instance_gpu_elements,
              (std::vector<std::uint32_t>{0, 1, 2, kNotGpuInstanced}));
    EXPECT_EQ(loaded.report.hidden_instances, (std::vector<std::uint32_t>{0, 2}));
    ASSERT_EQ(loaded.scene.instances.size(), scene.instances.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
        EXPECT_EQ(loaded.scene.instances[i].mesh_id, scene.instances[i].mesh_id) << i;
}

TEST(GltfHiddenInstances, WriterHidesSingularTransformsAndRefusesWhatCannotRoundTrip) {
    Scene scene;
    scene.meshes.push_back({"tri", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}});
    scene.instances = {{0, AffineTransform::translate({0, 0, 1})},
                       {0, AffineTransform::scale({1, 1, 0})},
                       {0, AffineTransform::scale({1e-11f, 1e-11f, 1e-11f})},
                       {0, AffineTransform::translate({2, 0, 0})}};
    EXPECT_THROW(scene.validate(), Error);
    EXPECT_NO_THROW(scene.validate(SingularTransforms::allowed));
    for (bool gpu_instancing : {false, true}) {
        SCOPED_TRACE(gpu_instancing ? "gpu instancing" : "nodes");
        const std::string path = test::scratch_path("hidden_singular.glb");
        write_gltf_scene(scene, path, {.gpu_instancing = gpu_instancing});
        const GltfLoadResult loaded = load_gltf_scene_with_report(path);
        EXPECT_EQ(loaded.report.hidden_instances, (std::vector<std::uint32_t>{1, 2}));
        ASSERT_EQ(loaded.scene.instances.size(), 4u);
        EXPECT_EQ(loaded.scene.instances[3].mesh_id, 0u);
        EXPECT_EQ(loaded.scene.instances[2].mesh_id, loaded.report.hidden_mesh);
    }
    auto expect_write_error = [](const Scene& bad, const std::string& phrase) {
        try {
            write_gltf_scene(bad, test::scratch_path("bad_hidden.glb"));
            ADD_FAILURE() << "no error (expected '" << phrase << "')";
        } catch (const Error& error) {
            EXPECT_NE(std::string(error.what()).find(phrase), std::string::npos) << error.what();
        }
    };
    Scene only_hidden;
    only_hidden.meshes.push_back({"hidden", {}, {}});
    only_hidden.instances.push_back({0, AffineTransform::identity()});
    expect_write_error(only_hidden, "no mesh has triangles");
    Scene unused_empty = scene;
    unused_empty.meshes.push_back({"unused", {}, {}});
    expect_write_error(unused_empty, "mesh 1 ('unused') has no triangles and no instance");
    Scene not_finite = scene;
    not_finite.instances[1].object_to_world.col_x.x = std::numeric_limits<float>::infinity();
    expect_write_error(not_finite, "instance 1 has a non-finite transform");
}

// ---- KHR_mesh_quantization positions ----------------------------------------------------------

TEST(GltfQuantization, BytesAndShortsAreDequantizedAsTheAccessorSays) {
    struct Case {
        int component_type;
        bool normalized;
        std::vector<std::int16_t> values;  // three VEC3s, stored as the component type
        std::vector<Vec3f> expected;       // in world space, node scale 2 applied
    };
    const std::vector<Case> cases = {
        {kByte,
         true,
         {0, 0, 0, 127, 0, -128, 0, 127, 64},
         {{0, 0, 0}, {2, 0, -2}, {0, 2, 128.f / 127}}},
        {kByte, false, {0, 0, 0, 100, 0, -3, 0, 7, 0}, {{0, 0, 0}, {200, 0, -6}, {0, 14, 0}}},
        {test::kUnsignedByte,
         true,
         {0, 0, 0, 255, 0, 51, 0, 255, 0},
         {{0, 0, 0}, {2, 0, 0.4f}, {0, 2, 0}}},
        {kShort,
         true,
         {0, 0, 0, 32767, 0, -32768, 0, 32767, 0},
         {{0, 0, 0}, {2, 0, -2}, {0, 2, 0}}},
        {test::kUnsignedShort,
         false,
         {0, 0, 0, 1000, 0, 2, 0, 3, 0},
         {{0, 0, 0}, {2000, 0, 4}, {0, 6, 0}}},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(std::to_string(c.component_type) + (c.normalized ? " normalized" : ""));
        GltfTestFile file;
        const bool is_byte = c.component_type == kByte || c.component_type == test::kUnsignedByte;
        // Elements padded to 4 bytes, as the specification requires for vertex attributes.
        std::vector<std::uint8_t> bytes(is_byte ? 12 : 24, 0);
        for (std::size_t v = 0; v < 3; ++v)
            for (std::size_t k = 0; k < 3; ++k) {
                const std::int16_t value = c.values[3 * v + k];
                if (is_byte)
                    bytes[4 * v + k] = std::uint8_t(value);
                else
                    std::memcpy(&bytes[8 * v + 2 * k], &value, 2);
            }
        const int view = file.add_view(bytes.data(), bytes.size(), is_byte ? 4 : 8);
        const int positions = file.add_accessor(view, c.component_type, 3, "VEC3");
        file.json["accessors"][positions]["normalized"] = c.normalized;
        file.add_mesh({primitive(positions)});
        file.add_node({{"mesh", 0}, {"scale", {2, 2, 2}}});
        file.add_scene({0});
        file.json["extensionsUsed"] = {"KHR_mesh_quantization"};
        file.json["extensionsRequired"] = {"KHR_mesh_quantization"};
        const Scene scene = load_gltf_scene(file.write_glb("quantized.glb"));
        for (std::size_t v = 0; v < 3; ++v)
            expect_near(
                scene.instances[0].object_to_world.transform_point(scene.meshes[0].positions[v]),
                c.expected[v], 1e-5f);
    }
}

// ---- Instanced copies of shared scenes against Embree -----------------------------------------

/// `scene` with its instances grouped by mesh, as `rebraid generate` writes them.
Scene grouped_by_mesh(Scene scene) {
    std::stable_sort(scene.instances.begin(), scene.instances.end(),
                     [](const Instance& a, const Instance& b) { return a.mesh_id < b.mesh_id; });
    return scene;
}

TEST(GltfGpuInstancing, InstancedCopiesOfSharedScenesHitLikeTheOriginals) {
    for (const char* name : {"fzk_haus.glb", "two_cylinder_engine.glb"}) {
        SCOPED_TRACE(name);
        const std::string source = std::string(REBRAID_SHARED_SCENES) + "/" + name;
        if (!std::filesystem::exists(source)) GTEST_SKIP() << "missing " << source;
        const Scene original = grouped_by_mesh(load_gltf_scene(source));
        const std::string instanced_path = test::scratch_path(std::string("gpu_") + name);
        const std::string nodes_path = test::scratch_path(std::string("nodes_") + name);
        write_gltf_scene(original, instanced_path, {.gpu_instancing = true});
        write_gltf_scene(original, nodes_path, {.gpu_instancing = false});
        const GltfLoadResult instanced =
            load_gltf_scene_with_report(instanced_path, {.keep_model = true});
        const Scene nodes = load_gltf_scene(nodes_path);
        // The instanced form really uses the extension for the meshes used more than once.
        EXPECT_LT(instanced.model->nodes.size(), original.instances.size());
        // Both forms: the same instances in the same order.
        ASSERT_EQ(instanced.scene.instances.size(), original.instances.size());
        ASSERT_EQ(nodes.instances.size(), original.instances.size());
        for (std::size_t i = 0; i < original.instances.size(); ++i) {
            const AffineTransform& a = original.instances[i].object_to_world;
            const AffineTransform& b = instanced.scene.instances[i].object_to_world;
            EXPECT_EQ(instanced.scene.instances[i].mesh_id, original.instances[i].mesh_id);
            EXPECT_EQ(nodes.instances[i].mesh_id, original.instances[i].mesh_id);
            EXPECT_TRUE(nodes.instances[i].object_to_world == a) << "instance " << i;
            const float size = std::max({length(a.col_x), length(a.col_y), length(a.col_z)});
            for (const Vec3f& p : {Vec3f{1, 0, 0}, Vec3f{0, 1, 0}, Vec3f{0, 0, 1}})
                expect_near(b.transform_vector(p), a.transform_vector(p), 2e-6f * size);
            expect_near(b.translation, a.translation, 0);
        }
        // Embree over the original's world-space triangles and over the instanced copy's.
        const glue::EmbreeFlatAccel reference(original);
        const std::vector<Ray> rays = test::varied_rays(reference, original.bounds(), 4000, 7);
        const glue::EmbreeFlatAccel copy(instanced.scene);
        test::expect_same_answers(original, rays, test::trace_all(reference, rays),
                                  test::trace_all(copy, rays),
                                  test::tolerance_for(original.bounds()));
    }
}

}  // namespace
}  // namespace rebraid
