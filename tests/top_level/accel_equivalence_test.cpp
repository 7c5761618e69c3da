// The project's structures against Embree's flat scene on the same rays: closest-hit
// distance, instance and primitive ids, and occlusion, on shared, default and generated
// scenes, with the kernels of every level this build and CPU can run (simd_level.h) and both
// triangle tests (triangle_test.h): the Möller test against Embree's default mode, the
// watertight one against its robust mode.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/core/triangle_test.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/generators/world_space_objects.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/hit_comparison.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

using AccelMaker = std::function<std::unique_ptr<Accel>(const Scene&)>;

struct NamedAccel {
    std::string name;
    AccelMaker make;
};

std::vector<NamedAccel> project_accels() {
    return {
        {"flat", [](const Scene& s) { return std::make_unique<FlatAccel>(s); }},
        {"twolevel",
         [](const Scene& s) { return std::make_unique<InstancedAccel>(build_two_level_accel(s)); }},
        {"rebraid",
         [](const Scene& s) { return std::make_unique<InstancedAccel>(build_rebraid_accel(s)); }},
        // Every mesh keeps its object space, as under the Embree glue.
        {"rebraid:world-single=0:world-copies=0",
         [](const Scene& s) {
             RebraidSettings settings;
             settings.world_space_single_instances = false;
             settings.world_space_copy_budget = 0.0f;
             return std::make_unique<InstancedAccel>(
                 build_rebraid_accel(s, own_object_bvh_builder(), settings));
         }},
        // The same, with every item's object subtree merged into the traced tree.
        {"rebraid:world-single=0:world-copies=0:merge-placed=1",
         [](const Scene& s) {
             RebraidSettings settings;
             settings.world_space_single_instances = false;
             settings.world_space_copy_budget = 0.0f;
             settings.merge_placed_instances = true;
             settings.merge_placed_node_budget = 1000.0f;
             return std::make_unique<InstancedAccel>(
                 build_rebraid_accel(s, own_object_bvh_builder(), settings));
         }},
    };
}

/// Switches a project structure to `level`'s kernels with the triangle test `test`.
void use_kernels(Accel& accel, SimdLevel level, TriangleTest test) {
    if (auto* flat = dynamic_cast<FlatAccel*>(&accel)) {
        flat->set_simd_level(level);
        flat->set_triangle_test(test);
    } else {
        auto& instanced = dynamic_cast<InstancedAccel&>(accel);
        instanced.set_simd_level(level);
        instanced.set_triangle_test(test);
    }
}

/// Same hits, bit for bit, and same occlusion answers.
void expect_identical_answers(const test::AccelAnswers& a, const test::AccelAnswers& b) {
    ASSERT_EQ(a.hits.size(), b.hits.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.hits.size(); ++i) {
        const Hit& x = a.hits[i];
        const Hit& y = b.hits[i];
        const bool same = std::bit_cast<std::uint32_t>(x.t) == std::bit_cast<std::uint32_t>(y.t) &&
                          x.instance_id == y.instance_id && x.prim_id == y.prim_id &&
                          std::bit_cast<std::uint32_t>(x.u) == std::bit_cast<std::uint32_t>(y.u) &&
                          std::bit_cast<std::uint32_t>(x.v) == std::bit_cast<std::uint32_t>(y.v) &&
                          a.occluded[i] == b.occluded[i];
        if (!same && differing++ < 5)
            ADD_FAILURE() << "ray " << i << ": t " << x.t << " / " << y.t << ", ids "
                          << x.instance_id << ":" << x.prim_id << " / " << y.instance_id << ":"
                          << y.prim_id << ", occluded " << int(a.occluded[i]) << " / "
                          << int(b.occluded[i]);
    }
    EXPECT_EQ(differing, 0u);
}

void expect_matches_embree_flat(const Scene& scene, const std::string& scene_name) {
    const glue::EmbreeFlatAccel robust_reference(scene);
    const glue::EmbreeFlatAccel default_reference(scene, {.is_robust = false, .device_config = {}});
    const std::vector<Ray> rays = test::varied_rays(robust_reference, scene.bounds(), 10000, 42);
    const test::AccelAnswers robust_expected = test::trace_all(robust_reference, rays);
    const test::AccelAnswers default_expected = test::trace_all(default_reference, rays);
    for (const NamedAccel& named : project_accels()) {
        const std::unique_ptr<Accel> accel = named.make(scene);
        for (TriangleTest triangle_test : {TriangleTest::moller, TriangleTest::watertight}) {
            const test::AccelAnswers& expected =
                triangle_test == TriangleTest::watertight ? robust_expected : default_expected;
            std::optional<test::AccelAnswers> avx2_answers;
            for (SimdLevel level : runnable_simd_levels()) {
                SCOPED_TRACE(scene_name + " / " + named.name + " / " +
                             std::string(simd_level_name(level)) + " / " +
                             std::string(triangle_test_name(triangle_test)));
                use_kernels(*accel, level, triangle_test);
                test::AccelAnswers answers = test::trace_all(*accel, rays);
                test::expect_same_answers(scene, rays, expected, answers,
                                          test::tolerance_for(scene.bounds()));
                // The AVX-512 kernels are the AVX2 sources compiled for AVX-512: same
                // arithmetic, so the same bits.
                if (level == SimdLevel::avx2) avx2_answers = std::move(answers);
                if (level == SimdLevel::avx512 && avx2_answers)
                    expect_identical_answers(*avx2_answers, answers);
            }
        }
    }
}

TEST(AccelEquivalence, DefaultSceneMatchesEmbreeFlat) {
    expect_matches_embree_flat(make_default_scene(), "default");
}

TEST(AccelEquivalence, GeneratedScenesMatchEmbreeFlat) {
    for (const test::NamedScene& named : test::generated_scenes())
        expect_matches_embree_flat(named.scene, named.name);
}

// Instances placed by the identity are entered with the world ray itself, the others with a
// mapped ray (instanced_accel.cpp): both kinds side by side, and objects all in world space.
TEST(AccelEquivalence, IdentityAndTransformedInstancesTogetherMatchEmbreeFlat) {
    Scene mixed = test::make_overlap_scene(24, 5);
    for (std::size_t i = 0; i < mixed.instances.size(); i += 3)
        mixed.instances[i].object_to_world = AffineTransform::identity();
    expect_matches_embree_flat(mixed, "every third instance at the identity");
    expect_matches_embree_flat(bake_instances_into_world_space(test::make_overlap_scene(24, 5)),
                               "objects in world space");
}

// Meshes placed by one instance each are built in world space by default
// (world_space_single_instances): alone, where a top of them is merged, and beside meshes
// that several instances place; and copies of shared meshes (world_space_copy_budget).
TEST(AccelEquivalence, MeshesPlacedOnceMatchEmbreeFlat) {
    expect_matches_embree_flat(test::make_overlap_scene(3, 7), "each mesh placed once");
    Scene mixed = test::make_overlap_scene(24, 5);
    for (std::size_t i = 0; i < 4; ++i) {
        mixed.meshes.push_back(mixed.meshes[mixed.instances[i].mesh_id]);
        mixed.instances[i].mesh_id = MeshId(mixed.meshes.size() - 1);
    }
    expect_matches_embree_flat(mixed, "four meshes placed once among shared ones");
    // Three meshes placed twice: the copies of the smallest fit world_space_copy_budget.
    expect_matches_embree_flat(test::make_overlap_scene(6, 7), "meshes placed twice");
}

class SharedSceneEquivalence : public testing::TestWithParam<std::string> {};

TEST_P(SharedSceneEquivalence, MatchesEmbreeFlat) {
    const std::string path = std::string(REBRAID_SHARED_SCENES) + "/" + GetParam();
    expect_matches_embree_flat(load_gltf_scene(path), GetParam());
}

INSTANTIATE_TEST_SUITE_P(SharedScenes, SharedSceneEquivalence,
                         testing::ValuesIn(test::shared_scene_files()),
                         [](const testing::TestParamInfo<std::string>& info) {
                             return test::test_name_of(info.param);
                         });

}  // namespace
}  // namespace rebraid

namespace rebraid {
namespace {

TEST(AccelEquivalence, SharedSceneFolderHoldsTheManifestScenes) {
    EXPECT_GE(test::shared_scene_files().size(), 9u) << "missing " << REBRAID_SHARED_SCENES;
}

}  // namespace
}  // namespace rebraid
