// Every command line README.md shows runs as written from the repository root: the `rebraid`
// commands here, in README order in a folder laid out like the repository's (`out/`, and the
// shared scenes at `../shared/scenes`), with smaller images, ray and frame counts as the README
// says; the other commands by the tests named in kCommandsTestedElsewhere.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.h"

namespace {

namespace fs = std::filesystem;
namespace test = rebraid::test;
using test::CommandResult;

constexpr std::string_view kRebraid = "./build/examples/rebraid";

/// README commands that are not `rebraid` runs, and the test or script that runs each.
const std::map<std::string, std::string> kCommandsTestedElsewhere{
    {"bash scripts/render-default.sh", "CI (.ci/run) on a fresh machine"},
    {"bash scripts/run-tests.sh", "CI (.ci/run) on a fresh machine"},
    {"cmake --build build --target minimal_example && ./build/examples/minimal_example",
     "Examples.MinimalExamplePrintsItsHits"},
    {"cmake --install build --prefix /tmp/rebraid-install",
     "InstallPackage.OutsideProjectBuildsAndRuns"},
    {"cmake -S examples/minimal -B build-minimal -DCMAKE_PREFIX_PATH=/tmp/rebraid-install",
     "InstallPackage.OutsideProjectBuildsAndRuns"},
    {"cmake --build build-minimal && ./build-minimal/minimal_example",
     "InstallPackage.OutsideProjectBuildsAndRuns"},
    {"cmake -S examples/dropin -B build-dropin-example -DCMAKE_PREFIX_PATH=/tmp/rebraid-install",
     "InstallPackage.OutsideProjectBuildsAndRuns"},
    {"cmake --build build-dropin-example && ./build-dropin-example/dropin_example --check",
     "InstallPackage.OutsideProjectBuildsAndRuns"},
    {"viewer -i out/brainstem/scene.xml -c out/brainstem/camera.cfg --instancing geometry -o "
     "out/embree.ppm",
     "SlowEmbreeTools.ViewersRenderTheExportedSharedScenesTheSame"},
    {"LD_PRELOAD=$PWD/build/lib/librebraid_preload.so REBRAID_PRELOAD_LOG=1 viewer -i "
     "out/brainstem/scene.xml -c out/brainstem/camera.cfg --instancing geometry -o "
     "out/rebraid.ppm",
     "SlowEmbreeTools.ViewersRenderTheExportedSharedScenesTheSame"},
};

/// Every line of README.md's ```sh blocks, in order.
std::vector<std::string> readme_shell_lines() {
    std::istringstream readme(test::read_text_file(fs::path(REBRAID_SOURCE_DIR) / "README.md"));
    std::vector<std::string> lines;
    bool is_in_shell_block = false;
    for (std::string line; std::getline(readme, line);) {
        if (line.rfind("```", 0) == 0) {
            is_in_shell_block = !is_in_shell_block && line == "```sh";
            continue;
        }
        if (is_in_shell_block && !line.empty()) lines.push_back(line);
    }
    return lines;
}

std::vector<std::string> split_words(const std::string& line) {
    std::istringstream words(line);
    std::vector<std::string> result;
    for (std::string word; words >> word;) result.push_back(word);
    return result;
}

/// Sets `option` to `value`, replacing the README's value or adding the option.
void set_option(std::vector<std::string>& arguments, const std::string& option,
                const std::string& value) {
    for (std::size_t i = 0; i + 1 < arguments.size(); ++i)
        if (arguments[i] == option) {
            arguments[i + 1] = value;
            return;
        }
    arguments.push_back(option);
    arguments.push_back(value);
}

/// The smaller sizes the README promises the tests use: a small image, one sample where the
/// command sets samples, few rays, repetitions and frames. The commands are otherwise as written.
std::vector<std::string> with_small_sizes(std::vector<std::string> arguments) {
    const std::string command = arguments.front();  // a copy: set_option may reallocate
    if (command == "render" || command == "animate") {
        set_option(arguments, "--width", "48");
        set_option(arguments, "--height", "27");
    }
    if (std::ranges::find(arguments, "--spp") != arguments.end())
        set_option(arguments, "--spp", "1");
    if (command == "bench") {
        set_option(arguments, "--rays", "500");
        set_option(arguments, "--repetitions", "1");
    }
    if (command == "animate") set_option(arguments, "--frames", "2");
    return arguments;
}

/// The file `-o` names, or "" when the command writes to standard output.
std::string output_file(const std::vector<std::string>& arguments) {
    for (std::size_t i = 0; i + 1 < arguments.size(); ++i)
        if (arguments[i] == "-o" || arguments[i] == "--output") return arguments[i + 1];
    return {};
}

TEST(ReadmeCommands, EveryRebraidCommandRunsAsWritten) {
    // The repository's layout: the commands' relative paths resolve as from its root.
    const fs::path dir = test::test_scratch_dir("readme_commands_test", true);
    const fs::path root = dir / "repository";
    fs::create_directories(root);
    fs::create_directories(dir / "shared");
    fs::create_directory_symlink(fs::absolute(REBRAID_SHARED_SCENES), dir / "shared" / "scenes");

    int command_count = 0;
    for (const std::string& line : readme_shell_lines()) {
        if (line.rfind(kRebraid, 0) != 0) continue;
        std::vector<std::string> arguments = split_words(line.substr(kRebraid.size()));
        const bool is_help = arguments.size() == 1 && arguments.front() == "--help";
        if (!is_help) arguments = with_small_sizes(arguments);
        const std::string output = output_file(arguments);
        // The README's commands write to out/, never over tracked files such as docs/images/.
        if (!output.empty()) {
            EXPECT_EQ(output.rfind("out/", 0), 0u) << line;
        }
        const CommandResult result =
            test::run_shell_in(root, "cd " + test::shell_quote(root.string()) + " && " +
                                         test::rebraid_command_line(arguments));
        ++command_count;
        EXPECT_EQ(result.exit_code, 0) << line << "\n" << result.err;
        EXPECT_TRUE(result.err.empty()) << line << "\n" << result.err;  // quiet when piped
        if (output.empty()) {
            EXPECT_FALSE(result.out.empty()) << line;
        } else {
            std::error_code error;
            EXPECT_GT(fs::file_size(root / output, error), 0u) << line << ": " << output;
        }
    }
    EXPECT_GE(command_count, 12) << "README.md has fewer rebraid commands than expected";
}

/// The pixels of the image at `path`, 8-bit RGB, row-major; empty when it cannot be read.
struct Rgb8Image {
    int width = 0, height = 0;
    std::vector<unsigned char> pixels;
};

Rgb8Image read_rgb8(const fs::path& path) {
    Rgb8Image image;
    auto input = OIIO::ImageInput::open(path.string());
    if (!input) return image;
    image.width = input->spec().width;
    image.height = input->spec().height;
    image.pixels.resize(std::size_t(image.width) * image.height * 3);
    if (!input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, image.pixels.data()))
        image.pixels.clear();
    return image;
}

/// "twolevel: 461120 nodes visited, ... by 129600 primary rays" -> 3.558: nodes per ray of
/// `accel` in render's summary.
double nodes_per_ray(const std::string& summary, const std::string& accel) {
    // From the exact counts ("N nodes visited, ... by R primary rays"), not the rounded
    // figure in parentheses, which would be rounded twice.
    const std::size_t line = summary.find("  " + accel + ": ");
    if (line == std::string::npos) return -1.0;
    const std::size_t by = summary.find(" by ", line);
    if (by == std::string::npos) return -1.0;
    const double nodes = std::stod(summary.substr(line + accel.size() + 4));
    return nodes / std::stod(summary.substr(by + 4));
}

// The heatmap picture is exact apart from its Mrays/s labels, so it must be what the build
// draws today; the path-traced pictures take minutes and are left to whoever renders them.
TEST(ReadmeCommands, HeatmapPictureAndItsFiguresAreWhatTheBuildGives) {
    std::string command;
    for (const std::string& line : readme_shell_lines())
        if (line.find("--compare twolevel,rebraid") != std::string::npos &&
            line.find("-o out/heatmap_compare.png") != std::string::npos)
            command = line;
    ASSERT_FALSE(command.empty()) << "README.md no longer shows the heatmap command";
    const fs::path dir = test::test_scratch_dir("readme_commands_test", true);
    fs::create_directories(dir / "shared");
    fs::create_directory_symlink(fs::absolute(REBRAID_SHARED_SCENES), dir / "shared" / "scenes");
    fs::create_directories(dir / "repository");
    const std::vector<std::string> arguments = split_words(command.substr(kRebraid.size()));
    const CommandResult result =
        test::run_shell_in(dir, "cd " + test::shell_quote((dir / "repository").string()) + " && " +
                                    test::rebraid_command_line(arguments));
    ASSERT_EQ(result.exit_code, 0) << result.err;

    const Rgb8Image built = read_rgb8(dir / "repository" / "out" / "heatmap_compare.png");
    const Rgb8Image shown =
        read_rgb8(fs::path(REBRAID_SOURCE_DIR) / "docs" / "images" / "heatmap_compare.png");
    ASSERT_FALSE(built.pixels.empty());
    ASSERT_FALSE(shown.pixels.empty());
    ASSERT_EQ(built.width, shown.width);
    ASSERT_EQ(built.height, shown.height);
    // Rows below the panel titles, whose Mrays/s vary from run to run and with them the width
    // of the title's box: at 480 pixels a panel's text scale is 2, and the box spans rows 8 to
    // 29 (4 rows of offset, then 2 of margin, 7 of glyph and 2 of margin, each times 2;
    // rebraid/render/heatmap.cpp, image_draw.cpp).
    constexpr int kTitleRows = 30;
    std::size_t differing = 0;
    for (std::size_t i = std::size_t(kTitleRows) * built.width * 3; i < built.pixels.size(); ++i)
        differing += built.pixels[i] != shown.pixels[i];
    EXPECT_EQ(differing, 0u) << "docs/images/heatmap_compare.png is not what " << command
                             << " draws now; render it again and copy it over";

    // The README's sentence about it: "re-braiding lowers the nodes a ray visits from A to B".
    char expected[64];
    std::snprintf(expected, sizeof expected, "from %.1f to %.1f",
                  nodes_per_ray(result.out, "twolevel"), nodes_per_ray(result.out, "rebraid"));
    EXPECT_NE(test::read_text_file(fs::path(REBRAID_SOURCE_DIR) / "README.md").find(expected),
              std::string::npos)
        << "README.md should say '" << expected << "'; the command printed\n"
        << result.out;
}

TEST(ReadmeCommands, EveryOtherCommandHasATest) {
    for (const std::string& line : readme_shell_lines()) {
        if (line.rfind(kRebraid, 0) == 0) continue;
        EXPECT_TRUE(kCommandsTestedElsewhere.contains(line))
            << "README.md shows a command no test runs: " << line;
    }
}

}  // namespace
