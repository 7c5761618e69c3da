// What a new user meets first: every input and output checked before the long work starts,
// options that would change nothing refused, and each error one line in the user's words.
#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <regex>
#include <string>
#include <vector>

#include "support/cli_runner.h"

namespace {

namespace fs = std::filesystem;
namespace test = rebraid::test;
using test::CommandResult;

fs::path scratch_dir() {
    return test::test_scratch_dir("cli_messages_test");
}

CommandResult run_rebraid(std::initializer_list<std::string> arguments, int timeout_seconds = 60) {
    return test::run_rebraid_in(scratch_dir(), arguments, timeout_seconds);
}

std::string shared_scene(const char* file) {
    return std::string(REBRAID_SHARED_SCENES) + "/" + file;
}

/// Expects exit code 1 and a message on stderr that starts with "rebraid: " and holds `phrase`,
/// without a function or type name of the code in front of a colon ("load_gltf_scene: ",
/// "RebraidSettings: ", "IncrementalTopLevel::build_frame: ").
void expect_error(const CommandResult& result, const std::string& phrase) {
    static const std::regex internal_name(R"(\b([a-z]+_[a-z_]+|[A-Z][a-z]+[A-Z]\w*)(::\w+)?: )");
    EXPECT_EQ(result.exit_code, 1) << result.err;
    EXPECT_EQ(result.err.rfind("rebraid: ", 0), 0u) << result.err;
    EXPECT_FALSE(std::regex_search(result.err, internal_name)) << result.err;
    EXPECT_NE(result.err.find(phrase), std::string::npos) << "no '" << phrase << "' in\n"
                                                          << result.err;
}

/// A small static glTF scene (two generated city blocks) in this test's folder.
std::string static_scene_file() {
    const fs::path path = scratch_dir() / "static.glb";
    const CommandResult result = test::run_rebraid_in(
        scratch_dir(), {"generate", "city", "--instances", "2", "-o", path.string()});
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return path.string();
}

/// A regular file standing where a command would need a directory.
std::string file_in_the_way() {
    const fs::path path = scratch_dir() / "not_a_directory";
    test::write_text_file(path, "x");
    return path.string();
}

// ---- Counts and numbers ----------------------------------------------------------------------

TEST(CliMessages, NegativeCountSaysWhatACountMustBe) {
    const CommandResult result = run_rebraid({"rays", "-n", "-5"});
    expect_error(result, "--count: -5 is out of range: it must be from 1 to");
    EXPECT_EQ(result.err.find("max_size"), std::string::npos) << result.err;
}

TEST(CliMessages, NegativeBudgetFactorGivesTheRangeInShortNumbers) {
    const CommandResult result = run_rebraid({"stats", "--budget-factor", "-1"});
    expect_error(result, "--budget-factor: -1 is out of range: it must be from 0 to 1e+06");
    EXPECT_LT(result.err.size(), 200u) << result.err;  // no 309-digit bound
}

TEST(CliMessages, TextWhereANumberBelongsIsNotANumber) {
    expect_error(run_rebraid({"render", "--width", "abc"}), "--width: 'abc' is not a whole number");
    expect_error(run_rebraid({"render", "--fov", "wide"}), "--fov: 'wide' is not a number");
    expect_error(run_rebraid({"bench", "--rays", "1.5"}), "--rays: '1.5' is not a whole number");
}

// ---- Names -----------------------------------------------------------------------------------

TEST(CliMessages, EnumOptionsListTheirNamesInHelpAndErrors) {
    // CLI11 would print "{extent->0,overlap->2,sah->1} OR {0,2,1}" or "--no-embree{false}".
    for (const char* command :
         {"trace", "stats", "render", "rays", "bench", "generate", "animate"}) {
        const CommandResult help = run_rebraid({command, "--help"});
        ASSERT_EQ(help.exit_code, 0) << command;
        EXPECT_EQ(help.out.find('{'), std::string::npos) << command << ":\n" << help.out;
        EXPECT_EQ(help.out.find("->"), std::string::npos) << command << ":\n" << help.out;
    }
    expect_error(run_rebraid({"stats", "--opening", "widest"}),
                 "--opening: 'widest' is not one of: extent, overlap, sah");
    expect_error(run_rebraid({"render", "--mode", "foo"}),
                 "--mode: 'foo' is not one of: ao, path, normals, heatmap");
    expect_error(run_rebraid({"generate", "city", "-o", "x.glb", "--placement", "random"}),
                 "--placement: 'random' is not one of: instanced, kind, world-space");
}

TEST(CliMessages, NoInternalFunctionNames) {
    const fs::path broken = scratch_dir() / "broken.glb";
    test::write_text_file(broken, "glTF but not really");
    const CommandResult scene = run_rebraid({"stats", broken.string()});
    expect_error(scene, "rebraid: scene file '" + broken.string() + "': ");
    EXPECT_EQ(scene.err.find("load_gltf"), std::string::npos) << scene.err;

    const CommandResult update = run_rebraid({"animate", "--update", "sideways"});
    expect_error(update, "--update: unknown update strategy 'sideways'");
    EXPECT_EQ(update.err.find("parse_"), std::string::npos) << update.err;

    const fs::path rays = scratch_dir() / "bad_rays.txt";
    test::write_text_file(rays, "0 0 5 0 0 -1 0\n");
    expect_error(run_rebraid({"trace", rays.string()}),
                 "ray file '" + rays.string() + "': line 1: ");

    const CommandResult kind = run_rebraid({"generate", "forest", "-o", "x.glb"});
    expect_error(kind, "unknown scene kind 'forest'; valid kinds: trees, crown");
    EXPECT_EQ(kind.err.find("parse_"), std::string::npos) << kind.err;
}

TEST(CliMessages, VersionIsPrinted) {
    const CommandResult result = run_rebraid({"--version"});
    EXPECT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(result.out.rfind("rebraid ", 0), 0u) << result.out;
    EXPECT_NE(result.out.find('.'), std::string::npos) << result.out;  // a version number
}

// ---- Files -----------------------------------------------------------------------------------

TEST(CliMessages, TraceOfASceneWithoutRayFileAsksForOne) {
    const std::string scene = shared_scene("fzk_haus.glb");
    const CommandResult result = run_rebraid({"trace", scene});
    expect_error(result, "trace needs a ray file: 'rebraid trace [SCENE] RAYS', and '" + scene +
                             "' is a scene");
    EXPECT_EQ(result.err.find("expected 8 fields"), std::string::npos) << result.err;
}

TEST(CliMessages, DirectoryAsRayFileIsNamed) {
    const fs::path dir = scratch_dir() / "rays_dir";
    fs::create_directories(dir);
    expect_error(run_rebraid({"trace", dir.string()}),
                 "ray file '" + dir.string() + "' is a directory, not a file");
}

TEST(CliMessages, OutputUnderAFileGivesTheReason) {
    const std::string blocker = file_in_the_way();
    expect_error(run_rebraid({"rays", "-n", "10", "-o", blocker + "/rays.txt"}),
                 "cannot create directory '" + blocker + "': Not a directory");
    expect_error(run_rebraid({"generate", "city", "-o", blocker + "/city.glb"}),
                 "cannot create directory '" + blocker + "': Not a directory");
}

TEST(CliMessages, DirectoryAsOutputFileIsNamed) {
    const fs::path dir = scratch_dir() / "out_dir";
    fs::create_directories(dir);
    expect_error(run_rebraid({"rays", "-n", "10", "-o", dir.string()}),
                 "ray file '" + dir.string() + "' is a directory; give a file name");
}

/// A new folder that every user may enter: the temporary folder's, since the build folder may
/// sit below one only its owner can enter, where the user the command runs as below would
/// be stopped by that folder instead of by the file under test.
fs::path folder_anyone_can_enter() {
    std::string pattern = (fs::temp_directory_path() / "rebraid_locked_XXXXXX").string();
    if (!::mkdtemp(pattern.data())) return {};
    fs::permissions(pattern, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                 fs::perms::others_read | fs::perms::others_exec);
    return pattern;
}

TEST(CliMessages, UnreadableAndUnwritableFilesGiveThePermissionReason) {
    const fs::path dir = folder_anyone_can_enter();
    ASSERT_FALSE(dir.empty()) << "cannot make a folder in " << fs::temp_directory_path();
    const fs::path rays = dir / "rays.txt";
    test::write_text_file(rays, "0 0 5 0 0 -1 0 inf\n");
    fs::permissions(rays, fs::perms::none);
    const fs::path read_only_dir = dir / "read_only";
    fs::create_directories(read_only_dir);
    fs::permissions(read_only_dir, fs::perms::owner_read | fs::perms::owner_exec |
                                       fs::perms::others_read | fs::perms::others_exec);
    // Root may read and write anything, so as root the command runs as user nobody.
    const std::string as_user =
        ::geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
    const CommandResult read = test::run_shell_in(
        dir,
        as_user + test::rebraid_command_line(std::vector<std::string>{"trace", rays.string()}));
    expect_error(read, "ray file '" + rays.string() + "': Permission denied");
    const CommandResult write = test::run_shell_in(
        dir, as_user + test::rebraid_command_line(std::vector<std::string>{
                           "rays", "-n", "10", "-o", (read_only_dir / "r.txt").string()}));
    expect_error(write, "r.txt': Permission denied");
    fs::permissions(read_only_dir, fs::perms::owner_all);
    fs::remove_all(dir);
}

// ---- Checked before the long work ------------------------------------------------------------
// Each command below would run for minutes if the check came after the work; a timeout turns
// that into exit code 124 instead of the 1 expected.

TEST(CliMessages, BenchChecksEveryScenePathBeforeBenchmarking) {
    const CommandResult result =
        run_rebraid({"bench", "default", "nosuch.glb", "--json", "--rays", "1000000000"}, 60);
    expect_error(result, "scene file 'nosuch.glb' does not exist");
    EXPECT_TRUE(result.out.empty()) << result.out;
}

TEST(CliMessages, RenderChecksTheOutputPathBeforeRendering) {
    const std::string blocker = file_in_the_way();
    expect_error(run_rebraid({"render", "-o", blocker + "/image.png", "--width", "32768",
                              "--height", "32768", "--spp", "65536"},
                             60),
                 "cannot create directory '" + blocker + "': Not a directory");
}

TEST(CliMessages, AnimateChecksPlotAndCsvBeforeTheFrames) {
    const std::string blocker = file_in_the_way();
    expect_error(run_rebraid({"animate", "--frames", "1000000", "--csv", blocker + "/f.csv"}, 60),
                 "cannot create directory '" + blocker + "'");
    // The plot tools are looked up first: a missing plot script stands in for missing matplotlib.
    ::setenv("REBRAID_PLOT_SCRIPT", (scratch_dir() / "no_such_plot.py").c_str(), 1);
    const CommandResult plot = run_rebraid(
        {"animate", "--frames", "1000000", "--plot", (scratch_dir() / "p.png").string()}, 60);
    ::unsetenv("REBRAID_PLOT_SCRIPT");
    expect_error(plot, "--plot needs the plot script");
}

// ---- Options that would change nothing ----------------------------------------------------

TEST(CliMessages, CompareRefusesAShadingMode) {
    expect_error(run_rebraid({"render", "--compare", "twolevel,rebraid", "--mode", "path"}),
                 "--compare draws heatmaps side by side, so --mode path does not apply");
}

TEST(CliMessages, RenderSaysWhatIsWrongWithImageNameAndCamera) {
    expect_error(run_rebraid({"render", "-o", (scratch_dir() / "image.foo").string()}),
                 "image.foo': name the image .png, or .exr for linear half-float");
    expect_error(run_rebraid({"render", "--look-from", "1,1,1", "--look-at", "1,1,1", "-o",
                              (scratch_dir() / "image.png").string()}),
                 "the camera's look-from and look-at points are the same point");
}

TEST(CliMessages, RenderOptionsTheModeIgnoresAreRefused) {
    expect_error(run_rebraid({"render", "--compare", "twolevel,rebraid", "--accel", "flat"}),
                 "--compare names the structures to draw, so --accel does not apply");
    expect_error(run_rebraid({"render", "--heat", "nodes"}),
                 "--heat chooses what a heatmap shows; it needs --mode heatmap or --compare");
    expect_error(run_rebraid({"render", "--bounces", "3"}),
                 "--bounces applies to --mode path only");
    expect_error(run_rebraid({"render", "--mode", "normals", "--spp", "4"}),
                 "--spp applies to --mode ao and --mode path only");
    expect_error(run_rebraid({"render", "--animation", "1"}),
                 "--animation chooses what --frames or --time plays; it needs one of them");
}

TEST(CliMessages, AnimationOptionsOnAStaticSceneAreRefused) {
    expect_error(run_rebraid({"render", "--frames", "2"}),
                 "--frames plays a glTF animation; the default scene has no animation");
    const std::string scene = static_scene_file();
    expect_error(run_rebraid({"render", scene, "--time", "1"}),
                 "--time plays a glTF animation; nothing in '" + scene + "' is animated");
    expect_error(run_rebraid({"render", "--time-step", "0.1"}),
                 "--time-step is the time between frames; it needs --frames");
    const fs::path rays = scratch_dir() / "rays.txt";
    test::write_text_file(rays, "0 0 5 0 0 -1 0 inf\n");
    expect_error(run_rebraid({"trace", scene, rays.string(), "--time", "1"}),
                 "--time poses an animated glTF scene; nothing in '" + scene + "' is animated");
}

TEST(CliMessages, BuildOptionsOfOtherStructuresAreRefused) {
    expect_error(run_rebraid({"stats", "--accel", "twolevel:opening=sah"}),
                 "accel 'twolevel:opening=sah': twolevel does not use opening; it is a setting "
                 "of rebraid");
    expect_error(run_rebraid({"stats", "--accel", "flat:object-builder=embree-high"}),
                 "flat does not use object-builder; it is a setting of twolevel or rebraid");
    expect_error(run_rebraid({"stats", "--accel", "twolevel", "--opening", "sah"}),
                 "--opening applies only to rebraid, which --accel twolevel does not build");
    expect_error(run_rebraid({"bench", "--accel", "flat,embree-flat", "--object-builder", "own"}),
                 "--object-builder applies only to twolevel or rebraid, which --accel "
                 "flat,embree-flat does not build");
    expect_error(run_rebraid({"stats", "--accel", "rebraid:open-threshold=-1"}),
                 "accel 'rebraid:open-threshold=-1': re-braiding setting open_threshold -1 must "
                 "be finite and >= 0");
    // A comparison of a structure with itself, under another name, is refused.
    expect_error(run_rebraid({"bench", "--accel", "twolevel,rebraid,rebraid:opening=sah"}),
                 "accel 'rebraid' and 'rebraid:opening=sah' build the same structure");
    expect_error(run_rebraid({"render", "--compare", "flat,flat"}),
                 "accel 'flat' and 'flat' build the same structure");
    expect_error(
        run_rebraid({"bench", "--accel", "rebraid,rebraid:opening=extent", "--opening", "extent"}),
        "accel 'rebraid' and 'rebraid:opening=extent' build the same structure");
    // Among several structures, an option is fine when one of them uses it.
    const CommandResult mixed = run_rebraid({"bench", "--accel", "twolevel,rebraid", "--opening",
                                             "extent", "--rays", "200", "--repetitions", "1"});
    EXPECT_EQ(mixed.exit_code, 0) << mixed.err;
}

TEST(CliMessages, RobustModeIsASettingOfEveryStructure) {
    // The project's structures in robust mode run the watertight triangle test, and say so.
    const CommandResult robust_flat = run_rebraid({"stats", "--accel", "flat:robust=1", "--json"});
    ASSERT_EQ(robust_flat.exit_code, 0) << robust_flat.err;
    EXPECT_EQ(nlohmann::json::parse(robust_flat.out).at("triangle_test"), "watertight");
    const CommandResult plain = run_rebraid({"stats", "--accel", "rebraid", "--json"});
    ASSERT_EQ(plain.exit_code, 0) << plain.err;
    EXPECT_EQ(nlohmann::json::parse(plain.out).at("triangle_test"), "moller");
    expect_error(run_rebraid({"stats", "--accel", "embree-flat:robust=2"}),
                 "accel 'embree-flat:robust=2': robust=2: valid values: 1, 0, true, false");
    // Embree's default flags are robust=0: naming them again is the same structure.
    expect_error(run_rebraid({"bench", "--accel", "embree-flat,embree-flat:robust=0"}),
                 "accel 'embree-flat' and 'embree-flat:robust=0' build the same structure");
    // Both modes side by side, on the same rays: they agree up to edge grazes.
    const CommandResult both =
        run_rebraid({"bench", "--accel", "embree-instanced,embree-instanced:robust=1", "--rays",
                     "400", "--repetitions", "1", "--json"});
    ASSERT_EQ(both.exit_code, 0) << both.err;
    const nlohmann::json rows = nlohmann::json::parse(both.out);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0].at("accel"), "embree-instanced");
    EXPECT_EQ(rows[1].at("accel"), "embree-instanced:robust=1");
    EXPECT_NEAR(rows[0].at("hits_primary").get<double>(), rows[1].at("hits_primary").get<double>(),
                4.0);
}

TEST(CliMessages, SpatialSplitsAreASettingOfTheOwnTriangleBvhs) {
    // On by default: the cut triangles' extra references take memory.
    const auto memory_of = [](const char* accel) {
        const CommandResult stats = run_rebraid({"stats", "--accel", accel, "--json"});
        EXPECT_EQ(stats.exit_code, 0) << stats.err;
        return nlohmann::json::parse(stats.out).at("memory_bytes").get<double>();
    };
    EXPECT_GT(memory_of("flat"), memory_of("flat:spatial-splits=0"));
    EXPECT_GT(memory_of("twolevel"), memory_of("twolevel:spatial-splits=0"));
    expect_error(run_rebraid({"stats", "--accel", "embree-flat:spatial-splits=0"}),
                 "embree-flat does not use spatial-splits; it is a setting of flat or twolevel or "
                 "rebraid");
    expect_error(run_rebraid({"stats", "--accel", "flat:spatial-splits=5"}),
                 "accel 'flat:spatial-splits=5': spatial-splits=5: not a fraction of the "
                 "triangles in [0, 4]");
    expect_error(run_rebraid({"bench", "--accel", "flat,flat:spatial-splits=0.2"}),
                 "accel 'flat' and 'flat:spatial-splits=0.2' build the same structure");
}

// ---- Outputs that explain themselves ---------------------------------------------------------

TEST(CliMessages, StatsSaysWhatTheBudgetCountsAndWhyEmbreeHasNoSah) {
    const CommandResult rebraid = run_rebraid({"stats"});
    ASSERT_EQ(rebraid.exit_code, 0) << rebraid.err;
    EXPECT_NE(rebraid.out.find("extra BRefs opening may add beyond one per instance"),
              std::string::npos)
        << rebraid.out;
    EXPECT_NE(rebraid.out.find("one per instance, plus those opening added"), std::string::npos)
        << rebraid.out;
    const CommandResult embree = run_rebraid({"stats", "--accel", "embree-flat"});
    ASSERT_EQ(embree.exit_code, 0) << embree.err;
    EXPECT_NE(embree.out.find("(no sah, nodes or leaves: embree-flat is Embree's own BVH"),
              std::string::npos)
        << embree.out;
}

TEST(CliMessages, CompareSaysEmbreeCountsNoWork) {
    const fs::path image = scratch_dir() / "compare.png";
    const CommandResult result =
        run_rebraid({"render", "--compare", "embree-flat,rebraid", "--width", "32", "--height",
                     "18", "-o", image.string()});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(result.out.find("embree-flat: work not counted"), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("rebraid: "), std::string::npos) << result.out;
    EXPECT_NE(result.out.find(" nodes visited"), std::string::npos) << result.out;
}

TEST(CliMessages, AnimateSummaryIsPrintedEvenWhenThePlotFails) {
    const fs::path failing_script = scratch_dir() / "failing_plot.py";
    test::write_text_file(failing_script, "import sys\nsys.exit(3)\n");
    ::setenv("REBRAID_PLOT_SCRIPT", failing_script.c_str(), 1);
    const CommandResult result = run_rebraid(
        {"animate", "--frames", "1", "--width", "8", "--height", "8", "--no-embree", "--update",
         "refit", "--json", "--plot", (scratch_dir() / "plot.png").string()});
    ::unsetenv("REBRAID_PLOT_SCRIPT");
    expect_error(result, "--plot: ");
    EXPECT_NE(result.out.find("\"mean_frame_ms\""), std::string::npos) << result.out;
}

// ---- Which camera ------------------------------------------------------------------------------

TEST(CliMessages, RenderNamesTheFileCameraAndHowToChooseAnother) {
    const std::string engine = shared_scene("two_cylinder_engine.glb");
    const fs::path image = scratch_dir() / "engine.png";
    const CommandResult own = run_rebraid(
        {"render", engine, "--width", "16", "--height", "9", "--spp", "1", "-o", image.string()});
    EXPECT_EQ(own.exit_code, 0) << own.err;
    EXPECT_NE(own.out.find("glTF camera 0 (the file's own; --fov or --look-from X,Y,Z for another "
                           "view)"),
              std::string::npos)
        << own.out;
    const CommandResult wider = run_rebraid({"render", engine, "--width", "16", "--height", "9",
                                             "--spp", "1", "--fov", "24", "-o", image.string()});
    EXPECT_EQ(wider.exit_code, 0) << wider.err;
    EXPECT_NE(wider.out.find("glTF camera 0, --fov 24,"), std::string::npos) << wider.out;
}

// ---- Output on a terminal and in a pipe -------------------------------------------------------

/// Runs `arguments` under `script`, so standard error is a terminal; returns what it showed.
std::string run_on_terminal(const std::vector<std::string>& arguments) {
    const std::string inner = test::rebraid_command_line(arguments);
    const CommandResult result = test::run_shell_in(
        scratch_dir(), "script -qefc " + test::shell_quote(inner) + " /dev/null");
    EXPECT_EQ(result.exit_code, 0) << result.out << result.err;
    return result.out;
}

TEST(CliMessages, RaysAndTraceSummarizeOnATerminalOnly) {
    const fs::path rays = scratch_dir() / "rays.txt";
    const CommandResult piped = run_rebraid({"rays", "-n", "10", "-o", rays.string()});
    EXPECT_EQ(piped.exit_code, 0) << piped.err;
    EXPECT_TRUE(piped.err.empty()) << piped.err;
    EXPECT_NE(run_on_terminal({"rays", "-n", "10", "-o", rays.string()})
                  .find("wrote 10 rays around the default scene to " + rays.string()),
              std::string::npos);

    const fs::path hits = scratch_dir() / "hits.txt";
    const CommandResult traced = run_rebraid({"trace", rays.string(), "-o", hits.string()});
    EXPECT_EQ(traced.exit_code, 0) << traced.err;
    EXPECT_TRUE(traced.err.empty()) << traced.err;
    EXPECT_NE(run_on_terminal({"trace", rays.string(), "-o", hits.string()})
                  .find("traced 10 rays through rebraid in default scene: "),
              std::string::npos);
}

TEST(CliMessages, BenchShowsProgressOnATerminalOnly) {
    const std::vector<std::string> bench{"bench", "--accel",       "flat", "--rays",
                                         "200",   "--repetitions", "1"};
    const CommandResult piped = test::run_rebraid_in(scratch_dir(), bench);
    EXPECT_EQ(piped.exit_code, 0) << piped.err;
    EXPECT_TRUE(piped.err.empty()) << piped.err;
    const std::string shown = run_on_terminal(bench);
    EXPECT_NE(run_on_terminal({"stats", "--accel", "flat"}).find("stats: building flat"),
              std::string::npos);
    EXPECT_NE(shown.find("bench: scene 1/1 (default scene), flat (1/1): building"),
              std::string::npos)
        << shown;
}

}  // namespace
