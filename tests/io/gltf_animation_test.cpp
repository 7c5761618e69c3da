// GltfAnimator against hand-computed poses of small files written here, error messages for
// bad animation data, and the animated shared scenes.

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numbers>
#include <thread>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_animation.h"
#include "support/gltf_animation_files.h"

namespace rebraid {
namespace {

using test::add_channel_animation;
using test::add_floats;
using test::add_integers;
using test::add_triangle_mesh;
using test::concat;
using test::GltfTestFile;
using test::load_animated;
using test::TwoJointSkin;
using test::vertex_1_joint_1_share;
using test::write_two_joint_skin_file;
using test::z_rotation;

constexpr float kTolerance = 1e-5f;

void expect_near(Vec3f actual, Vec3f expected, float tolerance = kTolerance) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

/// A file with one triangle mesh on node 0 (the only root) and one channel animating it.
std::string single_node_file(const std::string& name, const std::string& path,
                             const std::vector<float>& times, const std::vector<float>& values,
                             const std::string& type, const std::string& interpolation) {
    GltfTestFile file;
    const int mesh = add_triangle_mesh(file);
    file.add_node({{"mesh", mesh}});
    file.add_scene({0});
    add_channel_animation(file, 0, path, times, values, type, interpolation);
    return file.write_glb(name);
}

/// Instance 0's transform after posing the loaded scene at `time`.
AffineTransform pose_instance_0(const std::string& path, float time,
                                GltfAnimationSettings settings = {}) {
    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded, settings);
    Scene scene = loaded.scene;
    animator.apply(time, scene);
    return scene.instances[0].object_to_world;
}

// ---- Node channels --------------------------------------------------------------------------

TEST(GltfAnimation, LinearTranslationHalfway) {
    const std::string path = single_node_file("anim_linear.glb", "translation", {0, 2},
                                              {0, 0, 0, 4, 2, -2}, "VEC3", "LINEAR");
    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded);
    EXPECT_FLOAT_EQ(animator.duration(), 2.0f);
    EXPECT_TRUE(animator.animated());
    EXPECT_EQ(animator.moving_instances(), std::vector<InstanceId>{0});
    EXPECT_TRUE(animator.deformed_meshes().empty());
    Scene scene = loaded.scene;
    animator.apply(1.0f, scene);
    expect_near(scene.instances[0].object_to_world.translation, {2, 1, -1});
    expect_near(scene.instances[0].object_to_world.col_x, {1, 0, 0});
    animator.apply(0.5f, scene);
    expect_near(scene.instances[0].object_to_world.translation, {1, 0.5f, -0.5f});
}

TEST(GltfAnimation, StepHoldsEachKeyUntilTheNext) {
    const std::string path = single_node_file("anim_step.glb", "translation", {0, 1, 2},
                                              {1, 0, 0, 2, 0, 0, 3, 0, 0}, "VEC3", "STEP");
    EXPECT_FLOAT_EQ(pose_instance_0(path, 0.99f).translation.x, 1.0f);
    EXPECT_FLOAT_EQ(pose_instance_0(path, 1.0f).translation.x, 2.0f);
    EXPECT_FLOAT_EQ(pose_instance_0(path, 1.5f).translation.x, 2.0f);
    EXPECT_FLOAT_EQ(pose_instance_0(path, 2.0f).translation.x, 3.0f);
}

TEST(GltfAnimation, RotationSlerpsAtConstantAngularSpeed) {
    // 0 -> 90 degrees about z over 3 s: at 1 s, 30 degrees (a normalized lerp would give
    // atan(0.5 sin 45 / ...) = 26.6 degrees).
    const std::string path =
        single_node_file("anim_slerp.glb", "rotation", {0, 3},
                         concat(z_rotation(0), z_rotation(90)), "VEC4", "LINEAR");
    const AffineTransform pose = pose_instance_0(path, 1.0f);
    const float c = float(std::cos(std::numbers::pi / 6)), s = 0.5f;
    expect_near(pose.col_x, {c, s, 0});
    expect_near(pose.col_y, {-s, c, 0});
    expect_near(pose.col_z, {0, 0, 1});
}

TEST(GltfAnimation, RotationTakesTheShortestPath) {
    // The second key is the 90-degree rotation written as -q: halfway must be +45 degrees,
    // not a turn the long way round.
    std::vector<float> negated = z_rotation(90);
    for (float& component : negated) component = -component;
    const std::string path = single_node_file("anim_shortest.glb", "rotation", {0, 1},
                                              concat(z_rotation(0), negated), "VEC4", "LINEAR");
    const AffineTransform pose = pose_instance_0(path, 0.5f);
    const float h = float(std::sqrt(0.5));
    expect_near(pose.col_x, {h, h, 0});
    expect_near(pose.col_y, {-h, h, 0});
}

TEST(GltfAnimation, CubicSplineUsesTangents) {
    // x: v0 = 0 with out-tangent 1, v1 = 1 with in-tangent 0; y: 0 -> 2, zero tangents.
    // Key spacing td = 2. Hermite at s: h00 v0 + td h10 b0 + h01 v1 + td h11 a1.
    // s = 0.5: x = 2 * 0.125 * 1 + 0.5 * 1 = 0.75, y = 0.5 * 2 = 1.
    // s = 0.25: x = 2 * 0.140625 + 0.15625 = 0.4375, y = 0.15625 * 2 = 0.3125.
    const std::vector<float> values = {0, 0, 0, 0, 0, 0, 1, 0, 0,   // key 0: in, value, out
                                       0, 0, 0, 1, 2, 0, 0, 0, 0};  // key 1: in, value, out
    const std::string path =
        single_node_file("anim_cubic.glb", "translation", {0, 2}, values, "VEC3", "CUBICSPLINE");
    expect_near(pose_instance_0(path, 1.0f).translation, {0.75f, 1.0f, 0});
    expect_near(pose_instance_0(path, 0.5f).translation, {0.4375f, 0.3125f, 0});
    expect_near(pose_instance_0(path, 2.0f).translation, {1, 2, 0});
}

TEST(GltfAnimation, CubicSplineRotationIsNormalised) {
    // Zero tangents: halfway the spline is (q0 + q1) / 2, shorter than 1; normalised it is the
    // 45-degree rotation.
    const std::vector<float> zero(4, 0.0f);
    const std::vector<float> values = concat(concat(concat(zero, z_rotation(0)), zero),
                                             concat(concat(zero, z_rotation(90)), zero));
    const std::string path =
        single_node_file("anim_cubic_rot.glb", "rotation", {0, 1}, values, "VEC4", "CUBICSPLINE");
    const AffineTransform pose = pose_instance_0(path, 0.5f);
    const float h = float(std::sqrt(0.5));
    expect_near(pose.col_x, {h, h, 0});
    EXPECT_NEAR(length(pose.col_y), 1.0f, kTolerance);
}

TEST(GltfAnimation, TimesOutsideTheKeysClampWithoutLoop) {
    const std::string path = single_node_file("anim_clamp.glb", "translation", {1, 3},
                                              {5, 0, 0, 7, 0, 0}, "VEC3", "LINEAR");
    const GltfAnimationSettings no_loop{.loop = false};
    EXPECT_FLOAT_EQ(pose_instance_0(path, 0.0f, no_loop).translation.x, 5.0f);
    EXPECT_FLOAT_EQ(pose_instance_0(path, -4.0f, no_loop).translation.x, 5.0f);
    EXPECT_FLOAT_EQ(pose_instance_0(path, 2.0f, no_loop).translation.x, 6.0f);
    EXPECT_FLOAT_EQ(pose_instance_0(path, 10.0f, no_loop).translation.x, 7.0f);
}

TEST(GltfAnimation, LoopWrapsTimeIntoTheDuration) {
    const std::string path = single_node_file("anim_loop.glb", "translation", {0, 2},
                                              {0, 0, 0, 4, 0, 0}, "VEC3", "LINEAR");
    EXPECT_NEAR(pose_instance_0(path, 2.5f).translation.x, 1.0f, kTolerance);   // 0.5 s
    EXPECT_NEAR(pose_instance_0(path, -0.5f).translation.x, 3.0f, kTolerance);  // 1.5 s
    EXPECT_NEAR(pose_instance_0(path, 4.5f).translation.x, 1.0f, kTolerance);   // 0.5 s
    EXPECT_NEAR(pose_instance_0(path, 2.0f).translation.x, 4.0f, kTolerance);   // the end
}

TEST(GltfAnimation, ParentMotionMovesTheWholeSubtree) {
    GltfTestFile file;
    const int mesh = add_triangle_mesh(file);
    file.add_node({{"children", {1}}});  // 0: animated parent, no mesh
    file.add_node({{"mesh", mesh}, {"translation", {1, 0, 0}}, {"children", {2}}});     // 1
    file.add_node({{"mesh", mesh}, {"translation", {0, 0, 3}}, {"scale", {2, 2, 2}}});  // 2
    file.add_node({{"mesh", mesh}, {"translation", {7, 0, 0}}});  // 3: static root
    file.add_scene({0, 3});
    add_channel_animation(file, 0, "rotation", {0, 1}, concat(z_rotation(0), z_rotation(90)),
                          "VEC4", "STEP");
    const GltfLoadResult loaded = load_animated(file.write_glb("anim_subtree.glb"));
    const GltfAnimator animator(loaded);
    // Instances in depth-first order: node 1, node 2, node 3.
    EXPECT_EQ(animator.moving_instances(), (std::vector<InstanceId>{0, 1}));
    Scene scene = loaded.scene;
    animator.apply(1.0f, scene);
    // world(1) = Rz90 * T(1,0,0); world(2) = world(1) * T(0,0,3) * S(2).
    expect_near(scene.instances[0].object_to_world.translation, {0, 1, 0});
    expect_near(scene.instances[0].object_to_world.col_x, {0, 1, 0});
    expect_near(scene.instances[1].object_to_world.translation, {0, 1, 3});
    expect_near(scene.instances[1].object_to_world.col_x, {0, 2, 0});
    expect_near(scene.instances[1].object_to_world.col_z, {0, 0, 2});
    EXPECT_EQ(scene.instances[2].object_to_world, loaded.scene.instances[2].object_to_world);
}

TEST(GltfAnimation, AllAnimationsPlayTogetherOrOneAtATime) {
    GltfTestFile file;
    const int mesh = add_triangle_mesh(file);
    file.add_node({{"mesh", mesh}});
    file.add_node({{"mesh", mesh}});
    file.add_scene({0, 1});
    add_channel_animation(file, 0, "translation", {0, 1}, {0, 0, 0, 1, 0, 0}, "VEC3");
    add_channel_animation(file, 1, "translation", {0, 4}, {0, 0, 0, 0, 4, 0}, "VEC3");
    const GltfLoadResult loaded = load_animated(file.write_glb("anim_all.glb"));

    const GltfAnimator both(loaded, {.animation = -1});
    EXPECT_FLOAT_EQ(both.duration(), 4.0f);
    EXPECT_EQ(both.moving_instances(), (std::vector<InstanceId>{0, 1}));
    Scene scene = loaded.scene;
    both.apply(1.0f, scene);
    expect_near(scene.instances[0].object_to_world.translation, {1, 0, 0});
    expect_near(scene.instances[1].object_to_world.translation, {0, 1, 0});

    const GltfAnimator second(loaded, {.animation = 1});
    EXPECT_EQ(second.moving_instances(), std::vector<InstanceId>{1});
    scene = loaded.scene;
    second.apply(1.0f, scene);
    expect_near(scene.instances[0].object_to_world.translation, {0, 0, 0});
    expect_near(scene.instances[1].object_to_world.translation, {0, 1, 0});
}

TEST(GltfAnimation, FileWithoutAnimationNeverMoves) {
    GltfTestFile file;
    file.add_node({{"mesh", add_triangle_mesh(file)}, {"translation", {1, 2, 3}}});
    file.add_scene({0});
    const GltfLoadResult loaded = load_animated(file.write_glb("anim_none.glb"));
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.duration(), 0.0f);
    EXPECT_FALSE(animator.animated());
    Scene scene = loaded.scene;
    animator.apply(5.0f, scene);
    EXPECT_EQ(scene.instances[0].object_to_world, loaded.scene.instances[0].object_to_world);
}

// ---- Skinning -------------------------------------------------------------------------------

/// Poses the two-joint skin file (tests/support/gltf_animation_files.h) at `time`; returns the
/// scene.
Scene pose_skin(const std::string& name, const TwoJointSkin& skin, float time) {
    const GltfLoadResult loaded = load_animated(write_two_joint_skin_file(name, skin));
    const GltfAnimator animator(loaded);
    Scene scene = loaded.scene;
    animator.apply(time, scene);
    return scene;
}

/// World positions of the skin file's vertices at 1 s (joint 1 turned 90 degrees about z
/// around (1, 0, 0)): v0 stays, v2 = (1,0,0) + Rz90 (1,0,1), v1 blends (2,0,0) and (1,1,0).
void expect_bent_skin(const Scene& scene, MeshId mesh, double joint_1_share) {
    const float b = float(joint_1_share);
    const std::vector<Vec3f>& positions = scene.meshes[mesh].positions;
    expect_near(positions[0], {0, 0, 0});
    expect_near(positions[1], (1 - b) * Vec3f{2, 0, 0} + b * Vec3f{1, 1, 0});
    expect_near(positions[2], {1, 1, 1});
}

TEST(GltfSkinning, TwoJointsBendTheirVertices) {
    const GltfLoadResult loaded =
        load_animated(write_two_joint_skin_file("anim_skin.glb", TwoJointSkin{}));
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.mesh_ids(), std::vector<MeshId>{0});  // its only user keeps the mesh
    EXPECT_EQ(animator.deformed_meshes(), std::vector<MeshId>{0});
    EXPECT_TRUE(animator.moving_instances().empty());
    Scene scene = loaded.scene;
    animator.apply(1.0f, scene);
    // The skinned node's own translation (100, 0, 0) is ignored: identity, world positions.
    EXPECT_EQ(scene.instances[0].object_to_world, AffineTransform::identity());
    expect_bent_skin(scene, 0, 0.5);
    // 45 degrees: v2 = (1,0,0) + Rz45 (1,0,1).
    animator.apply(0.5f, scene);
    const float h = float(std::sqrt(0.5));
    expect_near(scene.meshes[0].positions[2], {1 + h, h, 1});
}

TEST(GltfSkinning, BindPoseReproducesTheMesh) {
    // At 0 s every joint is at its bind pose, so world(joint) * inverse bind = I.
    const Scene scene = pose_skin("anim_skin_bind.glb", TwoJointSkin{}, 0.0f);
    expect_near(scene.meshes[0].positions[0], {0, 0, 0});
    expect_near(scene.meshes[0].positions[1], {2, 0, 0});
    expect_near(scene.meshes[0].positions[2], {2, 0, 1});
}

TEST(GltfSkinning, ReadsByteJointsAndNormalizedWeights) {
    TwoJointSkin bytes{.joint_type = test::kUnsignedByte,
                       .weight_type = test::kUnsignedByte,
                       .raw_vertex_1_weights = {128, 127}};
    expect_bent_skin(pose_skin("anim_skin_u8.glb", bytes, 1.0f), 0, 127.0 / 255.0);
    TwoJointSkin shorts{.joint_type = test::kUnsignedShort,
                        .weight_type = test::kUnsignedShort,
                        .raw_vertex_1_weights = {16384, 49151}};
    expect_bent_skin(pose_skin("anim_skin_u16.glb", shorts, 1.0f), 0, 49151.0 / 65535.0);
    // Float weights that do not sum to 1 are rescaled: (1, 3) acts as (0.25, 0.75).
    TwoJointSkin unscaled{.raw_vertex_1_weights = {1, 3}};
    EXPECT_DOUBLE_EQ(vertex_1_joint_1_share(unscaled), 0.75);
    expect_bent_skin(pose_skin("anim_skin_rescale.glb", unscaled, 1.0f), 0, 0.75);
}

TEST(GltfSkinning, MissingInverseBindMatricesAreIdentity) {
    // Joint matrices are then the joints' world transforms: joint 1 = T(1,0,0) Rz90, so
    // v2 = (1,0,0) + Rz90 (2,0,1) = (1,2,1) and v1 = 0.5 (2,0,0) + 0.5 (1,2,0).
    const Scene scene =
        pose_skin("anim_skin_no_ibm.glb", {.has_inverse_bind_matrices = false}, 1.0f);
    expect_near(scene.meshes[0].positions[0], {0, 0, 0});
    expect_near(scene.meshes[0].positions[1], {1.5f, 1, 0});
    expect_near(scene.meshes[0].positions[2], {1, 2, 1});
}

TEST(GltfSkinning, SharedSkinnedMeshGetsAMeshPerInstance) {
    // Instances: node 0 (skinned), node 3 (skinned, same mesh), node 4 (static, same mesh).
    const TwoJointSkin skin{.extra_skinned_nodes = 1, .has_static_user = true};
    const GltfLoadResult loaded = load_animated(write_two_joint_skin_file("anim_shared.glb", skin));
    const GltfAnimator animator(loaded);
    ASSERT_EQ(loaded.scene.meshes.size(), 1u);
    EXPECT_EQ(animator.mesh_count(), 3u);
    EXPECT_EQ(animator.mesh_ids(), (std::vector<MeshId>{1, 2, 0}));
    EXPECT_EQ(animator.deformed_meshes(), (std::vector<MeshId>{1, 2}));
    Scene scene = loaded.scene;
    animator.apply(1.0f, scene);
    ASSERT_EQ(scene.meshes.size(), 3u);
    EXPECT_NO_THROW(scene.validate());
    EXPECT_EQ(scene.instances[1].mesh_id, 2u);
    expect_bent_skin(scene, 1, 0.5);
    expect_bent_skin(scene, 2, 0.5);
    EXPECT_EQ(scene.meshes[0].positions, loaded.scene.meshes[0].positions);  // static user
    EXPECT_EQ(scene.instances[2].object_to_world, loaded.scene.instances[2].object_to_world);

    // Later calls pose in place: same buffers, and a prepared scene stays as it is.
    const Vec3f* buffer = scene.meshes[1].positions.data();
    animator.apply(0.25f, scene);
    EXPECT_EQ(scene.meshes.size(), 3u);
    EXPECT_EQ(scene.meshes[1].positions.data(), buffer);
    EXPECT_EQ(scene.meshes[1].positions, scene.meshes[2].positions);
}

TEST(GltfSkinning, MorphTargetsApplyBeforeTheSkin) {
    // Vertex 2 morphs from (2,0,1) to (3,0,1), then joint 1 (90 degrees about z around
    // (1,0,0)) takes it to (1,0,0) + Rz90 (2,0,1) = (1,2,1). Skinning first would give
    // (1,1,1) + (1,0,0) = (2,1,1).
    const Scene scene = pose_skin("anim_skin_morph.glb", {.has_morph_target = true}, 1.0f);
    expect_near(scene.meshes[0].positions[2], {1, 2, 1});
}

// ---- Morph targets --------------------------------------------------------------------------

TEST(GltfMorph, AnimatedWeightsBlendTargetDeltas) {
    GltfTestFile file = test::morph_file_base({0, 0});
    file.add_node({{"mesh", 0}, {"translation", {5, 0, 0}}});
    file.add_scene({0});
    add_channel_animation(file, 0, "weights", {0, 1}, {0, 0, 1, 1}, "SCALAR");
    const GltfLoadResult loaded = load_animated(file.write_glb("anim_morph.glb"));
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.deformed_meshes(), std::vector<MeshId>{0});
    EXPECT_TRUE(animator.moving_instances().empty());
    Scene scene = loaded.scene;
    animator.apply(0.5f, scene);  // both weights 0.5
    expect_near(scene.meshes[0].positions[0], {0, 0, 1});
    expect_near(scene.meshes[0].positions[1], {1, 2, 0});
    expect_near(scene.meshes[0].positions[2], {0, 1, 0});
    // Not skinned: the node keeps its transform.
    EXPECT_EQ(scene.instances[0].object_to_world, loaded.scene.instances[0].object_to_world);
}

TEST(GltfMorph, NodeWeightsOverrideMeshWeights) {
    // Node 0 sets weights (0, 0.25); node 1 has none, so the mesh's (1, 0) apply. Both deform
    // the same mesh differently: node 1 gets a copy.
    GltfTestFile file = test::morph_file_base({1, 0});
    file.add_node({{"mesh", 0}, {"weights", {0, 0.25}}});
    file.add_node({{"mesh", 0}});
    file.add_scene({0, 1});
    const GltfLoadResult loaded = load_animated(file.write_glb("anim_morph_static.glb"));
    const GltfAnimator animator(loaded);
    EXPECT_FALSE(animator.animated());
    EXPECT_EQ(animator.mesh_ids(), (std::vector<MeshId>{0, 1}));
    Scene scene = loaded.scene;
    animator.apply(0.0f, scene);
    expect_near(scene.meshes[0].positions[0], {0, 0, 0});
    expect_near(scene.meshes[0].positions[1], {1, 1, 0});
    expect_near(scene.meshes[1].positions[0], {0, 0, 2});
    expect_near(scene.meshes[1].positions[1], {1, 0, 0});
}

// ---- Bad input --------------------------------------------------------------------------------

/// The message of the rebraid::Error that constructing an animator for `path` throws.
std::string animator_error(const std::string& path, GltfAnimationSettings settings = {}) {
    const GltfLoadResult loaded = load_animated(path);
    settings.file_label = path;
    try {
        const GltfAnimator animator(loaded, settings);
    } catch (const Error& error) {
        return error.what();
    }
    ADD_FAILURE() << "no rebraid::Error for " << path;
    return {};
}

void expect_mentions(const std::string& message, const std::vector<std::string>& parts) {
    for (const std::string& part : parts)
        EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

TEST(GltfAnimationErrors, InputTimesNotStrictlyIncreasing) {
    const std::string decreasing = single_node_file("anim_bad_order.glb", "translation", {0, 2, 1},
                                                    std::vector<float>(9, 0), "VEC3", "LINEAR");
    expect_mentions(animator_error(decreasing),
                    {decreasing, "animation 0", "channel 0", "not strictly increasing"});
    const std::string repeated = single_node_file("anim_bad_repeat.glb", "translation", {0, 1, 1},
                                                  std::vector<float>(9, 0), "VEC3", "STEP");
    expect_mentions(animator_error(repeated), {"channel 0", "not strictly increasing"});
}

TEST(GltfAnimationErrors, OutputCountsMustMatchTheKeys) {
    const std::string linear = single_node_file("anim_bad_count.glb", "translation", {0, 1},
                                                std::vector<float>(9, 0), "VEC3", "LINEAR");
    expect_mentions(animator_error(linear), {"channel 0", "output has 9 numbers, expected 6"});
    // CUBICSPLINE needs in-tangent, value and out-tangent per key.
    const std::string cubic = single_node_file("anim_bad_cubic.glb", "translation", {0, 1},
                                               std::vector<float>(6, 0), "VEC3", "CUBICSPLINE");
    expect_mentions(animator_error(cubic), {"expected 18"});
    const std::string type = single_node_file("anim_bad_type.glb", "translation", {0, 1},
                                              std::vector<float>(8, 0), "VEC4", "LINEAR");
    expect_mentions(animator_error(type), {"output of animation 0", "expected VEC3"});
}

TEST(GltfAnimationErrors, NonFiniteKeys) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::string output = single_node_file("anim_bad_nan.glb", "translation", {0, 1},
                                                {0, 0, 0, 1, nan, 0}, "VEC3", "LINEAR");
    expect_mentions(animator_error(output), {"output of animation 0", "element 1", "not finite"});
    const std::string input = single_node_file("anim_bad_nan_time.glb", "translation", {0, nan},
                                               {0, 0, 0, 1, 0, 0}, "VEC3", "LINEAR");
    expect_mentions(animator_error(input), {"input of animation 0", "not finite"});
}

TEST(GltfAnimationErrors, MissingTargetsAndSamplers) {
    GltfTestFile file;
    file.add_node({{"mesh", add_triangle_mesh(file)}});
    file.add_scene({0});
    add_channel_animation(file, 0, "translation", {0, 1}, {0, 0, 0, 1, 0, 0}, "VEC3");
    file.json["animations"][0]["channels"][0]["target"]["node"] = 9;
    expect_mentions(animator_error(file.write_glb("anim_bad_node.glb")),
                    {"channel 0", "missing node 9", "1 nodes"});
    file.json["animations"][0]["channels"][0]["target"]["node"] = 0;
    file.json["animations"][0]["channels"][0]["sampler"] = 4;
    expect_mentions(animator_error(file.write_glb("anim_bad_sampler.glb")), {"sampler 4"});
    file.json["animations"][0]["channels"][0]["sampler"] = 0;
    file.json["animations"][0]["samplers"][0]["interpolation"] = "SMOOTH";
    expect_mentions(animator_error(file.write_glb("anim_bad_interp.glb")),
                    {"unknown interpolation 'SMOOTH'"});
}

TEST(GltfAnimationErrors, ChannelsThatCannotApply) {
    GltfTestFile file;
    file.add_node({{"mesh", add_triangle_mesh(file)}});
    file.add_scene({0});
    add_channel_animation(file, 0, "weights", {0, 1}, {0, 1}, "SCALAR");
    expect_mentions(animator_error(file.write_glb("anim_bad_weights.glb")),
                    {"weights of node 0", "no mesh with morph targets"});
    file.json["animations"][0]["channels"][0]["target"]["path"] = "translation";
    file.json["nodes"][0]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    expect_mentions(animator_error(file.write_glb("anim_bad_matrix.glb")),
                    {"node 0", "has a matrix"});
}

TEST(GltfAnimationErrors, BadSkins) {
    const std::string past = write_two_joint_skin_file("anim_bad_joint.glb", {.vertex_2_joint = 5});
    expect_mentions(animator_error(past), {"node 0", "uses joint 5", "skin 0 has 2 joints"});
    GltfTestFile file = test::two_joint_skin_file({});
    file.json["meshes"][0]["primitives"][0]["attributes"].erase("JOINTS_0");
    expect_mentions(animator_error(file.write_glb("anim_bad_no_joints.glb")),
                    {"mesh 0", "no JOINTS_0"});
}

TEST(GltfAnimationErrors, ModelAnimationIndexAndScene) {
    const std::string path = single_node_file("anim_bad_use.glb", "translation", {0, 1},
                                              {0, 0, 0, 1, 0, 0}, "VEC3", "LINEAR");
    const GltfLoadResult without_model = load_gltf_scene_with_report(path);
    EXPECT_THROW(GltfAnimator{without_model}, Error);
    expect_mentions(animator_error(path, {.animation = 3}),
                    {"animation 3 does not exist", "1 animations"});

    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded);
    Scene other = loaded.scene;
    other.instances.push_back(other.instances[0]);
    EXPECT_THROW(animator.apply(0.5f, other), Error);
    Scene scene = loaded.scene;
    EXPECT_THROW(animator.apply(std::numeric_limits<float>::infinity(), scene), Error);
}

// ---- Parallel posing ------------------------------------------------------------------------

/// The two-joint skin rig with a 30,000-vertex mesh: every vertex split between the joints by
/// its own weight, plus a morph target animated alongside.
std::string write_large_skin_file(const std::string& name) {
    constexpr std::size_t kVertexCount = 30'000;
    GltfTestFile file;
    std::vector<Vec3f> positions, deltas;
    std::vector<std::int32_t> joints;
    std::vector<float> weights;
    for (std::size_t v = 0; v < kVertexCount; ++v) {
        const float x = float(v) * 1e-4f;
        positions.push_back({x, std::sin(x * 50), std::cos(x * 30)});
        deltas.push_back({0, 0.1f * std::cos(x * 70), 0});
        const float w = float(v % 1000) / 999.0f;
        joints.insert(joints.end(), {0, 1, 0, 0});
        weights.insert(weights.end(), {1 - w, w, 0, 0});
    }
    nlohmann::json morphed = test::primitive(file.add_positions(positions));
    morphed["attributes"]["JOINTS_0"] =
        add_integers(file, joints, test::kUnsignedShort, "VEC4", false);
    morphed["attributes"]["WEIGHTS_0"] = add_floats(file, weights, "VEC4");
    morphed["targets"] = {{{"POSITION", file.add_positions(deltas)}}};
    file.add_mesh({morphed});
    file.json["skins"].push_back({{"joints", {1, 2}}});
    file.add_node({{"mesh", 0}, {"skin", 0}});
    file.add_node({{"children", {2}}});
    file.add_node({{"translation", {1, 0, 0}}});
    file.add_scene({0, 1});
    add_channel_animation(file, 2, "rotation", {0, 1}, concat(z_rotation(0), z_rotation(120)),
                          "VEC4");
    add_channel_animation(file, 0, "weights", {0, 1}, {0, 1}, "SCALAR");
    return file.write_glb(name);
}

TEST(GltfAnimation, ParallelPosingMatchesSerialOnAnyThreadCount) {
    const GltfLoadResult loaded = load_animated(write_large_skin_file("anim_large_0.glb"));
    const GltfAnimator parallel(loaded, {.animation = -1, .parallel_grain = 256});
    const GltfAnimator serial(loaded, {.animation = -1, .parallel_grain = 1'000'000});
    auto pose = [&](const GltfAnimator& animator, int threads) {
        Scene scene = loaded.scene;
        tbb::task_arena(threads).execute([&] { animator.apply(0.7f, scene); });
        return scene.meshes[0].positions;
    };
    const std::vector<Vec3f> reference = pose(serial, 1);
    ASSERT_NE(reference, loaded.scene.meshes[0].positions);
    for (int threads : {1, 2, 4}) {
        const std::vector<Vec3f> positions = pose(parallel, threads);
        ASSERT_EQ(positions.size(), reference.size());
        EXPECT_EQ(std::memcmp(positions.data(), reference.data(), positions.size() * sizeof(Vec3f)),
                  0)
            << threads << " threads";
    }
}

TEST(GltfAnimation, ConcurrentPosesOfDistinctScenes) {
    const GltfLoadResult loaded = load_animated(write_large_skin_file("anim_large_1.glb"));
    const GltfAnimator animator(loaded, {.animation = -1, .parallel_grain = 512});
    const float times[2] = {0.3f, 0.9f};
    Scene expected[2] = {loaded.scene, loaded.scene};
    for (int k = 0; k < 2; ++k) animator.apply(times[k], expected[k]);
    Scene concurrent[2] = {loaded.scene, loaded.scene};
    std::thread other([&] { animator.apply(times[1], concurrent[1]); });
    animator.apply(times[0], concurrent[0]);
    other.join();
    for (int k = 0; k < 2; ++k)
        EXPECT_EQ(concurrent[k].meshes[0].positions, expected[k].meshes[0].positions) << k;
}

// ---- Shared animated scenes -----------------------------------------------------------------

std::string shared_scene(const std::string& name) {
    return std::string(REBRAID_SHARED_SCENES) + "/" + name;
}

bool same_scene(const Scene& a, const Scene& b) {
    if (a.meshes.size() != b.meshes.size() || a.instances.size() != b.instances.size())
        return false;
    for (std::size_t i = 0; i < a.instances.size(); ++i)
        if (!(a.instances[i].object_to_world == b.instances[i].object_to_world)) return false;
    for (std::size_t m = 0; m < a.meshes.size(); ++m)
        if (a.meshes[m].positions != b.meshes[m].positions) return false;
    return true;
}

class AnimatedSharedScene : public testing::TestWithParam<const char*> {};

TEST_P(AnimatedSharedScene, PosesAreFiniteChangingAndRepeatable) {
    const std::string path = shared_scene(GetParam());
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded, {.file_label = path});
    ASSERT_TRUE(animator.animated());
    ASSERT_GT(animator.duration(), 0.0f);
    const float d = animator.duration();
    Scene previous;
    Scene in_place = loaded.scene;  // posed again and again, like a renderer's frame loop
    bool anything_changed = false;
    for (float time : {0.0f, 0.23f * d, 0.5f * d, 0.81f * d, d}) {
        SCOPED_TRACE(time);
        Scene posed = loaded.scene;
        animator.apply(time, posed);
        EXPECT_NO_THROW(posed.validate());  // finite positions, finite invertible transforms
        Scene again = loaded.scene;
        animator.apply(time, again);
        EXPECT_TRUE(same_scene(posed, again));
        animator.apply(time, in_place);
        EXPECT_TRUE(same_scene(posed, in_place));
        if (!previous.meshes.empty() && !same_scene(previous, posed)) anything_changed = true;
        previous = std::move(posed);
    }
    EXPECT_TRUE(anything_changed);
}

INSTANTIATE_TEST_SUITE_P(Files, AnimatedSharedScene,
                         testing::Values("animated_morph_cube.glb", "brainstem.glb",
                                         "motion_capture_rom.glb"));

TEST(GltfAnimationSharedScenes, MorphCubeStartsAtItsBaseMesh) {
    // The file's weights are (0, 0) both as mesh default and at its first key.
    const std::string path = shared_scene("animated_morph_cube.glb");
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.deformed_meshes(), std::vector<MeshId>{0});
    Scene scene = loaded.scene;
    animator.apply(0.0f, scene);
    EXPECT_TRUE(same_scene(scene, loaded.scene));
    animator.apply(0.5f * animator.duration(), scene);
    EXPECT_NE(scene.meshes[0].positions, loaded.scene.meshes[0].positions);
}

TEST(GltfAnimationSharedScenes, MotionCaptureFrameZeroIsNearTheRestPose) {
    // In this file every channel's first key equals its node's TRS within 2e-3 (translations,
    // in scene units; the scene is ~95 units across) and 6e-5 (quaternion components): posing
    // at 0 s must land near the loaded transforms. All 26 mesh nodes lie below animated nodes.
    const std::string path = shared_scene("motion_capture_rom.glb");
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.moving_instances().size(), 26u);
    EXPECT_TRUE(animator.deformed_meshes().empty());
    Scene scene = loaded.scene;
    animator.apply(0.0f, scene);
    const float extent = length(loaded.scene.bounds().max - loaded.scene.bounds().min);
    for (InstanceId i = 0; i < scene.instances.size(); ++i) {
        const AffineTransform& posed = scene.instances[i].object_to_world;
        const AffineTransform& rest = loaded.scene.instances[i].object_to_world;
        EXPECT_LT(length(posed.translation - rest.translation), 2e-4f * extent) << i;
        EXPECT_LT(length(posed.col_x - rest.col_x), 1e-3f) << i;
        EXPECT_LT(length(posed.col_z - rest.col_z), 1e-3f) << i;
    }
}

TEST(GltfAnimationSharedScenes, BrainstemIsSkinnedInWorldSpace) {
    // 59 skinned nodes, one mesh each, every skin with an animated joint.
    const std::string path = shared_scene("brainstem.glb");
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded);
    EXPECT_EQ(animator.deformed_meshes().size(), 59u);
    EXPECT_EQ(animator.mesh_count(), loaded.scene.meshes.size());
    Scene scene = loaded.scene;
    animator.apply(0.4f * animator.duration(), scene);
    for (const Instance& instance : scene.instances)
        EXPECT_EQ(instance.object_to_world, AffineTransform::identity());
    // The posed figure stays a figure: about the rest pose's size, not collapsed or exploded.
    const float rest = length(loaded.scene.bounds().max - loaded.scene.bounds().min);
    const float posed = length(scene.bounds().max - scene.bounds().min);
    EXPECT_GT(posed, 0.5f * rest);
    EXPECT_LT(posed, 2.0f * rest);
}

TEST(GltfAnimationSharedScenes, BrainstemMatchesAnIndependentSkinning) {
    // Reference positions at 0 s (the file's first keys equal its rest TRS) from a separate
    // Python script that read the file's JSON and buffers directly: for each listed vertex,
    // sum_k w_k / sum(w) * world(joint_k) * inverseBind_k * position, world transforms
    // composed from the node TRS. Each listed mesh has one primitive.
    struct Reference {
        MeshId mesh;
        std::size_t vertex;
        Vec3f position;
    };
    const Reference references[] = {
        {0, 0, {0.074422f, 1.085032f, 0.053367f}},
        {0, 100, {0.055818f, 1.156802f, 0.090931f}},
        {0, 200, {0.094577f, 1.082762f, 0.059443f}},
        {5, 0, {-0.277444f, 0.530061f, 0.103063f}},
        {5, 100, {-0.110973f, 0.568608f, 0.134731f}},
        {5, 200, {0.109948f, 0.452640f, -0.005887f}},
        {30, 0, {-0.000953f, 1.452910f, -0.128866f}},
        {30, 100, {-0.025207f, 1.211508f, -0.226386f}},
        {30, 200, {0.004673f, 1.136904f, -0.058093f}},
    };
    const std::string path = shared_scene("brainstem.glb");
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
    const GltfLoadResult loaded = load_animated(path);
    const GltfAnimator animator(loaded);
    Scene scene = loaded.scene;
    animator.apply(0.0f, scene);
    for (const Reference& reference : references) {
        SCOPED_TRACE(testing::Message()
                     << "mesh " << reference.mesh << " vertex " << reference.vertex);
        // The script printed 6 decimals; float skinning differs from it by a few 1e-6.
        expect_near(scene.meshes[reference.mesh].positions[reference.vertex], reference.position,
                    2e-5f);
    }
}

}  // namespace
}  // namespace rebraid
