// The SAH's normaliser (docs/design.md, "SAH"): every structure over the same instances divides its cost
// by the half area of the box of the scene's world-space triangles.
#include "rebraid/top_level/bvh_stats.h"

#include <gtest/gtest.h>

#include "rebraid/generators/mesh_generators.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "rebraid/top_level/two_level_builder.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

BBox3f box_of_transformed_vertices(const Scene& scene) {
    BBox3f box;
    for (const Instance& instance : scene.instances)
        for (Vec3f p : scene.meshes[instance.mesh_id].positions)
            box.extend(instance.object_to_world.transform_point(p));
    return box;
}

TEST(InstancedSceneArea, IsTheBoxOfEveryTransformedVertex) {
    const Scene scene = test::make_overlap_scene(40, 3);
    const InstancedAccel two_level = build_two_level_accel(scene);
    std::vector<AffineTransform> transforms;
    for (const Instance& instance : scene.instances) transforms.push_back(instance.object_to_world);
    const double area = instanced_scene_half_area(two_level.top_level(), two_level.object_bvhs(),
                                                  two_level.instance_meshes(), transforms);
    const double expected = box_of_transformed_vertices(scene).half_area();
    EXPECT_NEAR(area, expected, 1e-5 * expected);
    // The rotated instances make the plain top's root box larger than the scene's.
    EXPECT_GT(two_level.top_level().bounds.half_area(), 1.01 * expected);
}

TEST(Sah, FlatAndTwoLevelAgreeOnOneUntransformedInstance) {
    Scene scene;
    scene.meshes.push_back(make_torus_knot({}));
    scene.instances.push_back({0, AffineTransform::identity()});
    const double flat = FlatAccel(scene).stats().sah.value();
    const double two_level = build_two_level_accel(scene).stats().sah.value();
    EXPECT_GT(flat, 1.0);
    EXPECT_NEAR(two_level, flat, 1e-9 * flat);
}

TEST(Sah, TwoLevelOfARotatedInstanceCostsMoreThanFlatOverTheSameTriangles) {
    // One rotated object: the flat BVH is built around the world-space triangles, the plain
    // top enters the object through the transformed AABB of its root and then tests
    // object-space boxes. With one normaliser the flat one must come out cheaper here; with
    // each structure's own root area the looser top would have hidden part of its cost.
    Scene scene;
    scene.meshes.push_back(make_torus_knot({}));
    scene.instances.push_back(
        {0, AffineTransform::rotate(normalize(Vec3f{1.0f, 2.0f, 3.0f}), 0.8f)});
    const double flat = FlatAccel(scene).stats().sah.value();
    const double two_level = build_two_level_accel(scene).stats().sah.value();
    EXPECT_GT(two_level, flat);
}

}  // namespace
}  // namespace rebraid
