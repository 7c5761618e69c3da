#include "embree_glue/reference/embree_ray_batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_dynamic_scene.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/dynamic/dynamic_scene.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/generators/twisting_object.h"
#include "rebraid/top_level/flat_accel.h"
#include "support/test_scenes.h"

namespace rebraid::glue {
namespace {

/// Random rays through `scene`, with an empty segment, a NaN one and a short one among them.
std::vector<Ray> rays_with_edge_cases(const Scene& scene) {
    std::vector<Ray> rays = generate_random_rays(scene.bounds(), 3000, 21);
    rays[5].tnear = 2.0f;
    rays[5].tfar = 1.0f;
    rays[9].tfar = std::numeric_limits<float>::quiet_NaN();
    rays[13].tfar = 1e-3f;
    return rays;
}

/// The batch answers as `accel`'s own queries do, ray for ray, whatever the ranges it is
/// traced in and the queries traced before.
void expect_batch_matches_accel(const Accel& accel, const Scene& scene) {
    const std::vector<Ray> rays = rays_with_edge_cases(scene);
    ASSERT_TRUE(EmbreeRayBatch::serves(accel));
    EmbreeRayBatch batch(accel, rays);
    ASSERT_EQ(batch.size(), rays.size());
    for (int round = 0; round < 2; ++round) {  // the second reads rays the first traced
        std::size_t hits = 0, occluded = 0;
        for (std::size_t begin = 0; begin < rays.size(); begin += 64) {
            const std::size_t end = std::min(begin + 64, rays.size());
            batch.intersect(begin, end);
            for (std::size_t i = begin; i < end; ++i) {
                const Hit expected = accel.intersect(rays[i]), got = batch.hit(i);
                ASSERT_EQ(got.is_hit(), expected.is_hit()) << "ray " << i;
                hits += got.is_hit();
                if (!expected.is_hit()) continue;
                EXPECT_EQ(got.t, expected.t) << "ray " << i;
                EXPECT_EQ(got.instance_id, expected.instance_id) << "ray " << i;
                EXPECT_EQ(got.prim_id, expected.prim_id) << "ray " << i;
                EXPECT_EQ(got.u, expected.u) << "ray " << i;
                EXPECT_EQ(got.v, expected.v) << "ray " << i;
            }
            batch.occlude(begin, end);
            for (std::size_t i = begin; i < end; ++i) {
                EXPECT_EQ(batch.is_occluded(i), accel.occluded(rays[i])) << "ray " << i;
                occluded += batch.is_occluded(i);
            }
        }
        // Both kinds of answer occur, so the comparison above could fail either way.
        EXPECT_GT(hits, 50u);
        EXPECT_LT(hits, rays.size());
        EXPECT_EQ(occluded, hits);
    }
    EXPECT_FALSE(batch.hit(5).is_hit());  // empty segment: never handed to Embree
    EXPECT_FALSE(batch.hit(9).is_hit());  // NaN segment
}

TEST(EmbreeRayBatch, AnswersAsTheFlatReferenceDoes) {
    const Scene scene = make_default_scene();
    expect_batch_matches_accel(EmbreeFlatAccel(scene), scene);
}

TEST(EmbreeRayBatch, AnswersAsTheInstancedReferenceDoes) {
    const Scene scene = make_default_scene();
    expect_batch_matches_accel(EmbreeInstancedAccel(scene), scene);
}

TEST(EmbreeRayBatch, AnswersAsTheDynamicStructuresDo) {
    const auto object = make_twisting_object({.path_segment_count = 96, .tube_segment_count = 8});
    DynamicScene dynamic(test::make_overlap_scene(30, 5), *object, {.copy_count = 3});
    for (EmbreeDynamicMode mode : {EmbreeDynamicMode::flat, EmbreeDynamicMode::instanced}) {
        SCOPED_TRACE(std::string(embree_dynamic_mode_name(mode)));
        EmbreeDynamicAccel accel(dynamic, mode);
        dynamic.pose(0.7f);
        accel.update();
        expect_batch_matches_accel(accel, dynamic.scene());
    }
}

TEST(EmbreeRayBatch, RejectsRaysTheReferenceRejects) {
    const Scene scene = make_default_scene();
    const EmbreeFlatAccel accel(scene);
    std::vector<Ray> rays = generate_random_rays(scene.bounds(), 10, 3);
    rays[4].tnear = -1.0f;
    EXPECT_THROW(accel.intersect(rays[4]), Error);
    EXPECT_THROW(EmbreeRayBatch(accel, rays), Error);
    rays[4].tnear = 0.0f;
    rays[7].org.y = std::numeric_limits<float>::infinity();
    EXPECT_THROW(EmbreeRayBatch(accel, rays), Error);
}

TEST(EmbreeRayBatch, ServesOnlyEmbreeStructures) {
    const Scene scene = make_default_scene();
    const FlatAccel flat(scene);
    EXPECT_FALSE(EmbreeRayBatch::serves(flat));
    EXPECT_THROW(EmbreeRayBatch(flat, std::vector<Ray>(1)), Error);
}

}  // namespace
}  // namespace rebraid::glue
