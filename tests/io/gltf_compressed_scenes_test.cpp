// Copies of shared scenes made by the glTF Transform command line (tests/io/assets, remade by
// make_assets.sh): quantized and meshopt-compressed, Draco-compressed, and GPU-instanced; and
// of a small textured grid, whose texture coordinates the copies must keep. Each
// copy is traced by Embree against the original (same instances, distances within the
// quantization error) and by the project's structures against Embree on the copy's own
// world-space triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/io/gltf_material.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/gltf_test_files.h"
#include "support/hit_comparison.h"
#include "support/test_rays.h"

namespace rebraid {
namespace {

struct CompressedCopy {
    const char* copy;      ///< in tests/io/assets
    const char* original;  ///< in the shared scenes
    bool is_gpu_instanced;
};

const CompressedCopy kCopies[] = {
    {"chinese_dragon_meshopt.glb", "chinese_dragon.glb", false},
    {"chinese_dragon_draco.glb", "chinese_dragon.glb", false},
    {"fzk_haus_instanced_meshopt.glb", "fzk_haus.glb", true},
};

/// Distance (relative to the scene's diagonal) under which two hits are at the same point,
/// given the copies' quantization.
constexpr float kTieDistance = 2e-4f;

float diagonal(const BBox3f& box) {
    return length(box.max - box.min);
}

class GltfCompressedCopy : public testing::TestWithParam<CompressedCopy> {};

TEST_P(GltfCompressedCopy, HitsLikeTheOriginal) {
    const CompressedCopy& files = GetParam();
    const std::string original_path = std::string(REBRAID_SHARED_SCENES) + "/" + files.original;
    if (!std::filesystem::exists(original_path)) GTEST_SKIP() << "missing " << original_path;
    const Scene original = load_gltf_scene(original_path);
    const GltfLoadResult copy = load_gltf_scene_with_report(std::string(REBRAID_SOURCE_DIR) +
                                                            "/tests/io/assets/" + files.copy);
    ASSERT_EQ(copy.scene.instances.size(), original.instances.size());
    EXPECT_EQ(copy.scene.instanced_triangle_count(), original.instanced_triangle_count());
    const bool has_gpu_elements = std::any_of(
        copy.report.instance_gpu_elements.begin(), copy.report.instance_gpu_elements.end(),
        [](std::uint32_t element) { return element != kNotGpuInstanced; });
    EXPECT_EQ(has_gpu_elements, files.is_gpu_instanced);

    // Embree over the original and over the copy, on the same rays.
    const glue::EmbreeFlatAccel original_embree(original);
    const glue::EmbreeFlatAccel copy_embree(copy.scene);
    const std::vector<Ray> rays = test::varied_rays(original_embree, original.bounds(), 4000, 5);
    const test::AccelAnswers expected = test::trace_all(original_embree, rays);
    const test::AccelAnswers actual = test::trace_all(copy_embree, rays);
    const float size = diagonal(original.bounds());
    std::vector<float> t_errors;
    std::size_t hit_disagreements = 0, other_instance = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const Hit& e = expected.hits[i];
        const Hit& a = actual.hits[i];
        if (e.is_hit() != a.is_hit()) {
            ++hit_disagreements;
            continue;
        }
        if (!e.is_hit()) continue;
        const float t_error = std::fabs(e.t - a.t) * length(rays[i].dir) / size;
        t_errors.push_back(t_error);
        // The same instance: instance order may differ, so compare where the instances are.
        // Where two instances' surfaces meet (a wall on a floor), quantization may pick
        // either: a tie, the hit point being the same.
        const BBox3f e_box = original.instance_bounds(e.instance_id);
        const BBox3f a_box = copy.scene.instance_bounds(a.instance_id);
        const bool same_place = diagonal({min(e_box.min, a_box.min), max(e_box.max, a_box.max)}) <=
                                diagonal(e_box) + 1e-3f * size;
        if (!same_place && t_error > kTieDistance) ++other_instance;
    }
    ASSERT_GT(t_errors.size(), rays.size() / 10);
    std::sort(t_errors.begin(), t_errors.end());
    const float p99 = t_errors[t_errors.size() * 99 / 100];
    std::printf(
        "%s: %zu hits, %zu hit/miss disagreements, %zu on another instance, distance "
        "error / scene diagonal: median %.2g, 99th percentile %.2g, max %.2g\n",
        files.copy, t_errors.size(), hit_disagreements, other_instance,
        t_errors[t_errors.size() / 2], p99, t_errors.back());

    // 14-bit positions (both tools' default) are off by up to half a step, 1 / 32766 of
    // the mesh's extent, per axis; along a ray that grows by 1 / cos of the incidence angle.
    EXPECT_LE(double(hit_disagreements + other_instance), 0.01 * double(t_errors.size()));
    EXPECT_LE(t_errors[t_errors.size() / 2], 3e-5f);
    EXPECT_LE(p99, 2e-4f);

    // The copy's own world-space triangles: the project's structure matches Embree on them.
    const InstancedAccel rebraided(build_rebraid_accel(copy.scene));
    test::expect_same_answers(copy.scene, rays, actual, test::trace_all(rebraided, rays),
                              test::tolerance_for(copy.scene.bounds()));
}

INSTANTIATE_TEST_SUITE_P(Assets, GltfCompressedCopy, testing::ValuesIn(kCopies),
                         [](const testing::TestParamInfo<CompressedCopy>& info) {
                             return test::test_name_of(info.param.copy);
                         });

// ---- Texture coordinates ----------------------------------------------------------------------

struct LoadedUvs {
    Scene scene;
    std::vector<std::array<float, 2>> uvs;  ///< of mesh 0
};

LoadedUvs load_base_colour_uvs(const std::string& asset) {
    GltfLoadOptions options;
    options.keep_model = true;
    const GltfLoadResult loaded = load_gltf_scene_with_report(
        std::string(REBRAID_SOURCE_DIR) + "/tests/io/assets/" + asset, options);
    std::vector<std::vector<std::array<float, 2>>> uvs =
        read_gltf_base_colour_uvs(loaded, read_gltf_materials(loaded));
    return {loaded.scene, uvs.empty() ? std::vector<std::array<float, 2>>{} : uvs[0]};
}

// The copies' texture coordinates are the original's within their quantization (12 bits over
// [0, 1] for both tools' defaults): Draco decodes them with its mesh, meshopt stores them as
// normalized shorts. Vertices are matched by world position (Draco reorders its points).
TEST(GltfCompressedTextures, CopiesKeepTheBaseColourTextureCoordinates) {
    const LoadedUvs original = load_base_colour_uvs("textured_grid.glb");
    ASSERT_EQ(original.scene.meshes.size(), 1u);
    ASSERT_EQ(original.uvs.size(), original.scene.meshes[0].positions.size());
    for (const char* copy_name : {"textured_grid_draco.glb", "textured_grid_meshopt.glb"}) {
        SCOPED_TRACE(copy_name);
        const LoadedUvs copy = load_base_colour_uvs(copy_name);
        ASSERT_EQ(copy.scene.instances.size(), 1u);
        const std::vector<Vec3f>& positions = copy.scene.meshes[0].positions;
        ASSERT_EQ(copy.uvs.size(), positions.size());
        const AffineTransform& to_world = copy.scene.instances[0].object_to_world;
        std::size_t matched = 0;
        float largest_error = 0.0f;
        for (std::size_t v = 0; v < positions.size(); ++v) {
            const Vec3f world = to_world.transform_point(positions[v]);
            std::size_t nearest = 0;
            float nearest_distance = std::numeric_limits<float>::infinity();
            for (std::size_t o = 0; o < original.uvs.size(); ++o) {
                const float distance = length(original.scene.meshes[0].positions[o] - world);
                if (distance < nearest_distance) nearest_distance = distance, nearest = o;
            }
            if (nearest_distance > 1e-3f) continue;
            ++matched;
            for (int c = 0; c < 2; ++c)
                largest_error =
                    std::max(largest_error, std::abs(copy.uvs[v][c] - original.uvs[nearest][c]));
        }
        EXPECT_EQ(matched, positions.size());
        EXPECT_LE(largest_error, 1.0f / 4095.0f);
    }
}

// ---- Broken compressed files ------------------------------------------------------------------

/// An asset opened for editing: its JSON and BIN chunk.
test::GltfTestFile open_asset(const std::string& name) {
    std::ifstream in(std::string(REBRAID_SOURCE_DIR) + "/tests/io/assets/" + name,
                     std::ios::binary);
    const std::vector<unsigned char> bytes{std::istreambuf_iterator<char>(in),
                                           std::istreambuf_iterator<char>()};
    std::uint32_t json_length = 0, bin_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    std::memcpy(&bin_length, bytes.data() + 20 + json_length, 4);
    test::GltfTestFile file;
    file.json = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_length);
    const auto bin = bytes.begin() + 28 + json_length;
    file.bin.assign(bin, bin + bin_length);
    return file;
}

using Breakage = std::function<void(test::GltfTestFile&)>;

void expect_each_breakage_fails(const std::string& asset,
                                const std::vector<std::pair<std::string, Breakage>>& cases) {
    for (const auto& [phrase, breakage] : cases) {
        SCOPED_TRACE(phrase);
        test::GltfTestFile file = open_asset(asset);
        breakage(file);
        const std::string path = file.write_glb("broken_" + asset);
        try {
            load_gltf_scene(path);
            ADD_FAILURE() << "no error loading " << path;
        } catch (const Error& error) {
            EXPECT_NE(std::string(error.what()).find(phrase), std::string::npos) << error.what();
        }
    }
}

TEST(GltfCompressedErrors, BrokenDracoData) {
    const char* draco = "KHR_draco_mesh_compression";
    auto extension = [draco](test::GltfTestFile& f) -> nlohmann::json& {
        return f.json["meshes"][0]["primitives"][0]["extensions"][draco];
    };
    expect_each_breakage_fails(
        "chinese_dragon_draco.glb",
        {{"corrupt Draco data",
          [](test::GltfTestFile& f) { std::fill(f.bin.begin(), f.bin.begin() + 64, 0); }},
         {"corrupt Draco data",
          [](test::GltfTestFile& f) { f.json["bufferViews"][0]["byteLength"] = 300; }},
         {"accessors say 9999 and 19994",
          [](test::GltfTestFile& f) { f.json["accessors"][1]["count"] = 9999; }},
         {"references bufferView 9",
          [&](test::GltfTestFile& f) { extension(f)["bufferView"] = 9; }},
         {"has no attribute 4",
          [&](test::GltfTestFile& f) { extension(f)["attributes"]["POSITION"] = 4; }},
         {"needs the Draco attribute id of POSITION",
          [&](test::GltfTestFile& f) {
              extension(f)["attributes"] = {{"NORMAL", 0}};
          }},
         {"only mode TRIANGLES",
          [](test::GltfTestFile& f) { f.json["meshes"][0]["primitives"][0]["mode"] = 5; }},
         {"more than max_vertices",
          [](test::GltfTestFile& f) { f.json["accessors"][1]["count"] = 4'000'000'000u; }}});
}

TEST(GltfCompressedErrors, BrokenMeshoptData) {
    const char* meshopt = "EXT_meshopt_compression";
    auto view = [meshopt](test::GltfTestFile& f, int v) -> nlohmann::json& {
        return f.json["bufferViews"][v]["extensions"][meshopt];
    };
    expect_each_breakage_fails(
        "chinese_dragon_meshopt.glb",
        {{"the ATTRIBUTES data is corrupt",
          [](test::GltfTestFile& f) {
              std::fill(f.bin.begin() + 23508, f.bin.begin() + 23508 + 64, 0xFF);
          }},
         {"the TRIANGLES data is corrupt",
          [&](test::GltfTestFile& f) { view(f, 0)["byteLength"] = 20000; }},
         {"claims 1000000000 elements",
          [&](test::GltfTestFile& f) { view(f, 1)["count"] = 1'000'000'000; }},
         {"unknown mode 'POINTS'", [&](test::GltfTestFile& f) { view(f, 1)["mode"] = "POINTS"; }},
         {"multiple of 4", [&](test::GltfTestFile& f) { view(f, 1)["byteStride"] = 6; }},
         {"filter QUATERNION needs byteStride 8",
          [&](test::GltfTestFile& f) {
              view(f, 1)["byteStride"] = 12;
              view(f, 1)["filter"] = "QUATERNION";
          }},
         {"needs mode ATTRIBUTES",
          [&](test::GltfTestFile& f) { view(f, 0)["filter"] = "EXPONENTIAL"; }},
         {"references buffer 7", [&](test::GltfTestFile& f) { view(f, 1)["buffer"] = 7; }},
         {"runs past the end of buffer 0",
          [&](test::GltfTestFile& f) { view(f, 1)["byteOffset"] = 1'000'000; }},
         {"not a whole number", [&](test::GltfTestFile& f) { view(f, 1)["count"] = -3; }},
         // A view that reads the fallback buffer without being compressed.
         {"runs past the end of buffer 1",
          [](test::GltfTestFile& f) { f.json["bufferViews"][1].erase("extensions"); }}});
}

TEST(GltfCompressedErrors, DracoTextureCoordinatesNamingAMissingAttribute) {
    test::GltfTestFile file = open_asset("textured_grid_draco.glb");
    file.json["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
             ["attributes"]["TEXCOORD_0"] = 9;
    GltfLoadOptions options;
    options.keep_model = true;
    const GltfLoadResult loaded =
        load_gltf_scene_with_report(file.write_glb("broken_textured_grid_draco.glb"), options);
    try {
        read_gltf_base_colour_uvs(loaded, read_gltf_materials(loaded));
        ADD_FAILURE() << "no error";
    } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find("has no attribute 9 (TEXCOORD_0)"),
                  std::string::npos)
            << error.what();
    }
}

}  // namespace
}  // namespace rebraid
