// End-to-end tests of `rebraid bench`: tiny runs of the built binary, checking its JSON and
// table output.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.h"

namespace {

namespace fs = std::filesystem;
namespace test = rebraid::test;
using test::CommandResult;

CommandResult run_rebraid(std::initializer_list<std::string> arguments) {
    return test::run_rebraid_in(test::test_scratch_dir("cli_bench_test"), arguments);
}

std::string shared_scene(const char* file) {
    return std::string(REBRAID_SHARED_SCENES) + "/" + file;
}

/// The structures `rebraid bench` runs by default.
const std::vector<std::string> kRequiredAccels{"embree-flat", "embree-instanced", "flat",
                                               "twolevel", "rebraid"};

TEST(CliBench, JsonHasOneObjectPerSceneAndStructureWithEveryKey) {
    const std::string small = shared_scene("motion_capture_rom.glb");
    const std::string dragon = shared_scene("chinese_dragon.glb");
    const CommandResult result = run_rebraid({"bench", small, dragon, "--rays", "600",
                                              "--repetitions", "1", "--json", "--threads", "2"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json json = nlohmann::json::parse(result.out);  // throws on extra text
    ASSERT_TRUE(json.is_array());
    ASSERT_EQ(json.size(), 2 * kRequiredAccels.size()) << result.out;

    std::map<std::string, std::set<std::string>> accels_per_scene;
    std::map<std::string, std::uint64_t> embree_flat_hits;
    for (const nlohmann::json& row : json) {
        for (const char* key :
             {"scene", "accel", "build_ms", "sah", "mrays_primary", "mrays_diffuse", "rays_primary",
              "rays_diffuse", "hits_primary", "triangles", "instances"})
            ASSERT_TRUE(row.contains(key)) << key << " missing in " << row.dump();
        const std::string scene = row.at("scene").get<std::string>();
        const std::string accel = row.at("accel").get<std::string>();
        EXPECT_TRUE(accels_per_scene[scene].insert(accel).second) << accel << " twice";
        EXPECT_EQ(row.at("rays_primary").get<std::uint64_t>(), 600u);
        EXPECT_EQ(row.at("rays_diffuse").get<std::uint64_t>(), 600u);
        EXPECT_GT(row.at("mrays_primary").get<double>(), 0.0) << accel;
        EXPECT_GT(row.at("mrays_diffuse").get<double>(), 0.0) << accel;
        EXPECT_GE(row.at("build_ms").get<double>(), 0.0) << accel;
        EXPECT_EQ(row.at("threads").get<int>(), 2);
        const bool is_embree = accel.rfind("embree-", 0) == 0;
        // Embree's BVHs cannot be inspected: their SAH is null; the project's are >= 1.
        if (is_embree)
            EXPECT_TRUE(row.at("sah").is_null()) << accel;
        else
            EXPECT_GE(row.at("sah").get<double>(), 1.0) << accel;
        const bool is_two_level = accel == "twolevel" || accel == "rebraid";
        EXPECT_EQ(row.contains("top_build_ms"), is_two_level) << accel;
        EXPECT_EQ(row.contains("object_builder"), is_two_level) << accel;
        if (!is_embree) {
            EXPECT_TRUE(row.contains("nodes")) << accel;
        }
        // Work per diffuse ray: counted by the project's structures, null for Embree's; only
        // two-level ones enter objects, and with one instance (the dragon) the plain top
        // enters it at most once per ray.
        for (const char* key : {"nodes_per_diffuse_ray", "triangles_per_diffuse_ray",
                                "object_entries_per_diffuse_ray"})
            ASSERT_EQ(row.at(key).is_null(), is_embree) << key << " of " << accel;
        if (!is_embree) {
            EXPECT_GT(row.at("nodes_per_diffuse_ray").get<double>(), 0.0) << accel;
            EXPECT_GT(row.at("triangles_per_diffuse_ray").get<double>(), 0.0) << accel;
            const double entries = row.at("object_entries_per_diffuse_ray").get<double>();
            if (is_two_level) {
                EXPECT_GT(entries, 0.0) << accel;
            } else {
                EXPECT_EQ(entries, 0.0) << accel;
            }
            if (accel == "twolevel" && scene.find("chinese_dragon") != std::string::npos) {
                EXPECT_LE(entries, 1.0);
            }
        }
        if (accel == "embree-flat") embree_flat_hits[scene] = row.at("hits_primary");
    }
    ASSERT_EQ(accels_per_scene.size(), 2u);
    for (const auto& [scene, accels] : accels_per_scene)
        EXPECT_EQ(accels, std::set<std::string>(kRequiredAccels.begin(), kRequiredAccels.end()))
            << scene;
    // Every structure traces the same rays: primary hit counts agree up to edge grazes.
    for (const nlohmann::json& row : json) {
        const auto expected = double(embree_flat_hits.at(row.at("scene")));
        EXPECT_GT(expected, 0.0);
        EXPECT_NEAR(row.at("hits_primary").get<double>(), expected, 0.01 * 600) << row.at("accel");
    }
}

TEST(CliBench, TableListsTheChosenStructuresWithTheirBuilder) {
    const CommandResult result = run_rebraid(
        {"bench", shared_scene("motion_capture_rom.glb"), "--rays", "300", "--repetitions", "1",
         "--accel", "flat,twolevel", "--object-builder", "embree-medium"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(result.out.find("motion_capture_rom.glb"), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("\n  flat "), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("twolevel/embree-medium"), std::string::npos) << result.out;
    EXPECT_EQ(result.out.find("embree-flat"), std::string::npos) << result.out;
    EXPECT_EQ(result.out.find("rebraid "), std::string::npos) << result.out;
}

TEST(CliBench, TakingTurnsAndOneAtATimeMeasureTheSameStructures) {
    const auto bench = [](bool one_at_a_time) {
        std::vector<std::string> args = {"bench",         shared_scene("motion_capture_rom.glb"),
                                         "--rays",        "300",
                                         "--repetitions", "2",
                                         "--accel",       "embree-flat,flat,rebraid",
                                         "--json"};
        if (one_at_a_time) args.push_back("--one-at-a-time");
        const CommandResult result =
            test::run_rebraid_in(test::test_scratch_dir("cli_bench_test"), args);
        EXPECT_EQ(result.exit_code, 0) << result.err;
        return nlohmann::json::parse(result.out);
    };
    const nlohmann::json turns = bench(false);
    const nlohmann::json alone = bench(true);
    ASSERT_EQ(turns.size(), 3u);
    ASSERT_EQ(alone.size(), 3u);
    for (std::size_t i = 0; i < turns.size(); ++i) {
        const nlohmann::json& a = turns[i];
        const nlohmann::json& b = alone[i];
        EXPECT_EQ(a.at("timing"), "taking_turns");
        EXPECT_EQ(b.at("timing"), "one_at_a_time");
        // Each row still describes its own structure, whichever way it was timed.
        EXPECT_EQ(a.at("accel"), b.at("accel"));
        for (const char* key : {"hits_primary", "hits_diffuse", "nodes_per_diffuse_ray",
                                "triangles_per_diffuse_ray", "object_entries_per_diffuse_ray"})
            EXPECT_EQ(a.at(key), b.at(key)) << a.at("accel") << " " << key;
        EXPECT_EQ(a.value("structure_hash", nlohmann::json()),
                  b.value("structure_hash", nlohmann::json()))
            << a.at("accel");
        EXPECT_GT(a.at("mrays_primary").get<double>(), 0.0) << a.at("accel");
        EXPECT_GT(a.at("mrays_diffuse").get<double>(), 0.0) << a.at("accel");
    }
}

TEST(CliBench, SavedRaysAreTheRaysItTraced) {
    const fs::path dir = test::test_scratch_dir("cli_bench_test") / "saved_rays";
    fs::remove_all(dir);
    const std::string scene = shared_scene("motion_capture_rom.glb");
    const CommandResult bench =
        run_rebraid({"bench", scene, "--rays", "300", "--repetitions", "1", "--accel", "flat",
                     "--json", "--save-rays", dir.string()});
    ASSERT_EQ(bench.exit_code, 0) << bench.err;
    const nlohmann::json row = nlohmann::json::parse(bench.out).at(0);
    const std::map<std::string, std::string> hit_keys{{"primary", "hits_primary"},
                                                      {"diffuse", "hits_diffuse"}};
    for (const auto& [kind, key] : hit_keys) {
        const fs::path rays = dir / ("motion_capture_rom." + kind + ".rays");
        ASSERT_TRUE(fs::exists(rays)) << rays;
        // Tracing the saved rays again finds as many hits as the bench counted on them.
        const CommandResult trace = run_rebraid({"trace", scene, rays.string(), "--accel", "flat"});
        ASSERT_EQ(trace.exit_code, 0) << trace.err;
        std::istringstream lines(trace.out);
        std::size_t ray_count = 0, hit_count = 0;
        for (std::string line; std::getline(lines, line); ++ray_count)
            hit_count += line.rfind("inf ", 0) != 0;
        EXPECT_EQ(ray_count, 300u) << kind;
        EXPECT_EQ(hit_count, row.at(key).get<std::size_t>()) << kind;
    }
}

TEST(CliBench, ObjectBuilderAndRebraidSettingsReachTheJson) {
    const CommandResult result =
        run_rebraid({"bench", shared_scene("motion_capture_rom.glb"), "--rays", "200",
                     "--repetitions", "1", "--accel", "rebraid", "--object-builder", "embree-high",
                     "--budget-factor", "0", "--json"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json json = nlohmann::json::parse(result.out);
    ASSERT_EQ(json.size(), 1u);
    EXPECT_EQ(json[0].at("object_builder"), "embree-high");
    // Budget factor 0: nothing may be opened.
    ASSERT_TRUE(json[0].contains("opened")) << json.dump();
    EXPECT_EQ(json[0].at("opened").get<std::uint64_t>(), 0u);
}

TEST(CliBench, UnknownStructureFailsBeforeLoadingAnything) {
    const CommandResult result =
        run_rebraid({"bench", "/no/such/scene.glb", "--accel", "flat,no-such-bvh"});
    EXPECT_EQ(result.exit_code, 1);
    EXPECT_NE(result.err.find("unknown accel 'no-such-bvh'"), std::string::npos) << result.err;
    EXPECT_EQ(result.err.find("scene.glb"), std::string::npos) << result.err;
}

TEST(CliBench, BadValuesAreParseErrors) {
    EXPECT_NE(run_rebraid({"bench", "--rays", "0"}).exit_code, 0);
    EXPECT_NE(run_rebraid({"bench", "--repetitions", "0"}).exit_code, 0);
    EXPECT_NE(run_rebraid({"bench", "--object-builder", "nope"}).exit_code, 0);
    EXPECT_NE(run_rebraid({"bench", "--open-threshold", "-1"}).exit_code, 0);
}

}  // namespace
