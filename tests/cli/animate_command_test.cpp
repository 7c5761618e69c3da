// `rebraid animate` end to end at tiny sizes: JSON summary keys, CSV rows per frame and
// method, plots, and bad options.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "rebraid/dynamic/object_bvh_update.h"
#include "rebraid/generators/mesh_generators.h"
#include "support/cli_runner.h"
#include "support/gltf_test_files.h"

namespace {

using rebraid::Mesh;
using rebraid::test::GltfTestFile;

namespace fs = std::filesystem;
namespace test = rebraid::test;
using test::CommandResult;

/// A scratch folder of this test alone (ctest runs tests in parallel processes).
fs::path scratch_dir(const std::string& test_name) {
    const fs::path dir = fs::path(REBRAID_TEST_TMP) / ("animate_" + test_name);
    fs::create_directories(dir);
    return dir;
}

std::vector<std::string> split(const std::string& text, char separator) {
    std::vector<std::string> parts;
    std::istringstream in(text);
    for (std::string part; std::getline(in, part, separator);) parts.push_back(part);
    return parts;
}

/// A small static scene (a ground grid and a few tori) as a .glb, so the runs take well
/// under a second: the default scene has over a million triangles.
std::string small_static_scene_file(const std::string& test_name) {
    GltfTestFile file;
    std::vector<int> roots;
    for (const Mesh& mesh :
         {rebraid::make_ground_grid({.size = 10.0f, .cell_count = 16}),
          rebraid::make_torus({.major_segment_count = 24, .minor_segment_count = 8})}) {
        std::vector<std::uint32_t> indices;
        for (const rebraid::Triangle& t : mesh.triangles)
            indices.insert(indices.end(), t.begin(), t.end());
        const int position = file.add_positions(mesh.positions);
        const int index = file.add_indices(indices);
        file.add_mesh({{{"attributes", {{"POSITION", position}}}, {"indices", index}}});
    }
    roots.push_back(file.add_node({{"mesh", 0}}));
    for (int i = 0; i < 5; ++i)
        roots.push_back(file.add_node({{"mesh", 1}, {"translation", {-4.0 + 2.0 * i, 0.5, 0.0}}}));
    file.add_scene(roots);
    // One file per test: ctest runs the tests in parallel processes.
    return file.write_glb("animate_static_" + test_name + ".glb");
}

TEST(AnimateCommand, JsonHasOneObjectPerMethodWithTheSummaryKeys) {
    const fs::path dir = scratch_dir("json");
    const CommandResult result = test::run_rebraid_in(
        dir, {"animate", "--static", small_static_scene_file("json"), "--frames", "2", "--copies",
              "2", "--width", "32", "--height", "18", "--update", "refit,rotate", "--json"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json json = nlohmann::json::parse(result.out);
    ASSERT_TRUE(json.is_array());
    std::set<std::string> methods;
    for (const nlohmann::json& entry : json) {
        for (const char* key : {"method", "mean_frame_ms", "max_frame_ms", "mean_update_ms",
                                "mean_top_ms", "mean_render_ms", "final_sah"})
            EXPECT_TRUE(entry.contains(key)) << key << " missing in " << entry.dump();
        const std::string method = entry["method"];
        methods.insert(method);
        EXPECT_GE(entry["max_frame_ms"].get<double>(), entry["mean_frame_ms"].get<double>());
        EXPECT_GT(entry["mean_render_ms"].get<double>(), 0.0);
        // Only the project's structures can be inspected for their SAH.
        EXPECT_EQ(entry["final_sah"].is_null(), method.rfind("embree", 0) == 0) << method;
        if (!entry["final_sah"].is_null()) {
            EXPECT_GE(entry["final_sah"].get<double>(), 1.0);
        }
    }
    const std::set<std::string> expected = {
        "embree-flat",    "embree-flat-refit",         "embree-instanced",
        "twolevel+refit", "twolevel+rotate",           "rebraid+refit",
        "rebraid+rotate", "rebraid-incremental+refit", "rebraid-incremental+rotate"};
    EXPECT_EQ(methods, expected);
}

TEST(AnimateCommand, RunsEveryUpdateStrategyByDefault) {
    const fs::path dir = scratch_dir("strategies");
    const CommandResult result = test::run_rebraid_in(
        dir, {"animate", "--static", small_static_scene_file("strategies"), "--frames", "1",
              "--copies", "1", "--width", "8", "--height", "8", "--top", "rebraid", "--no-embree",
              "--static-builder", "embree-high", "--json"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    std::set<std::string> methods;
    for (const nlohmann::json& entry : nlohmann::json::parse(result.out))
        methods.insert(entry["method"].get<std::string>());
    std::set<std::string> expected;
    for (rebraid::UpdateStrategy strategy : rebraid::kUpdateStrategies)
        expected.insert("rebraid+" + std::string(rebraid::update_strategy_name(strategy)));
    EXPECT_EQ(methods, expected);
    EXPECT_TRUE(expected.count("rebraid+treelet"));
}

TEST(AnimateCommand, CsvHasOneRowPerFrameAndMethod) {
    const fs::path dir = scratch_dir("csv");
    const fs::path csv = dir / "frames.csv";
    const CommandResult result = test::run_rebraid_in(
        dir, {"animate", "--static", small_static_scene_file("csv"), "--frames", "3", "--copies",
              "1", "--width", "16", "--height", "9", "--top", "rebraid", "--update", "auto",
              "--no-embree", "--csv", csv.string()});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(result.out.find("rebraid+auto"), std::string::npos) << result.out;
    const std::vector<std::string> lines = split(test::read_text_file(csv), '\n');
    ASSERT_EQ(lines.size(), 1u + 3u);
    const std::vector<std::string> header = split(lines[0], ',');
    const std::vector<std::string> expected_header = {"frame",        "time",      "method",
                                                      "animation_ms", "update_ms", "top_ms",
                                                      "render_ms",    "frame_ms",  "sah"};
    EXPECT_EQ(header, expected_header);
    for (std::size_t i = 1; i < lines.size(); ++i) {
        const std::vector<std::string> fields = split(lines[i], ',');
        ASSERT_EQ(fields.size(), header.size()) << lines[i];
        EXPECT_EQ(fields[0], std::to_string(i - 1));
        EXPECT_EQ(fields[2], "rebraid+auto");
        EXPECT_GT(std::stod(fields[8]), 1.0);
        // frame_ms is the sum of the four parts.
        const double sum = std::stod(fields[3]) + std::stod(fields[4]) + std::stod(fields[5]) +
                           std::stod(fields[6]);
        EXPECT_NEAR(std::stod(fields[7]), sum, 1e-3 * sum + 1e-3);
    }
}

TEST(AnimateCommand, PlotWritesAPng) {
    // scripts/install-deps.sh installs python3-matplotlib: a missing one is a failure.
    ASSERT_EQ(std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1"), 0)
        << "no matplotlib for /usr/bin/python3 (Debian's python3-matplotlib)";
    const fs::path dir = scratch_dir("plot");
    const fs::path png = dir / "frames.png";
    fs::remove(png);
    const CommandResult result = test::run_rebraid_in(
        dir, {"animate", "--static", small_static_scene_file("plot"), "--frames", "2", "--copies",
              "1", "--width", "16", "--height", "9", "--update", "refit", "--top", "twolevel",
              "--plot", png.string()});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string bytes = test::read_text_file(png);
    ASSERT_GE(bytes.size(), 8u);
    EXPECT_EQ(bytes.substr(1, 3), "PNG");
}

TEST(AnimateCommand, BadOptionsExitWithOneAndAMessage) {
    const fs::path dir = scratch_dir("bad");
    const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
        {{"--update", "sideways"}, "sideways"},
        {{"--top", "flat"}, "flat"},
        {{"--dynamic", (dir / "missing.glb").string()}, "missing.glb"},
        {{"--static", (dir / "nothing.glb").string()}, "nothing.glb"},
        {{"--size", "2"}, "--size: 2 is out of range: it must be from 0 to 1"},
        {{"--size", "0"}, "--size must be more than 0"},
        {{"--static-builder", "quick"}, "quick"},
    };
    const std::string static_scene = small_static_scene_file("bad");
    for (const auto& [arguments, message] : cases) {
        std::string command = test::shell_quote(REBRAID_CLI);
        command += " animate --frames 1 --width 8 --height 8";
        if (arguments.front() != "--static") {
            command += " --static ";
            command += test::shell_quote(static_scene);
        }
        for (const std::string& argument : arguments) {
            command += ' ';
            command += test::shell_quote(argument);
        }
        command += " >/dev/null 2>";
        command += test::shell_quote((dir / "stderr.txt").string());
        const int status = std::system(command.c_str());
        ASSERT_TRUE(status != -1 && WIFEXITED(status)) << command;
        EXPECT_EQ(WEXITSTATUS(status), 1) << command;
        EXPECT_NE(test::read_text_file(dir / "stderr.txt").find(message), std::string::npos)
            << command << ": " << test::read_text_file(dir / "stderr.txt");
    }
    const CommandResult frames = test::run_rebraid_in(dir, {"animate", "--frames", "0"});
    EXPECT_NE(frames.exit_code, 0);
    EXPECT_FALSE(frames.err.empty());
}

}  // namespace
