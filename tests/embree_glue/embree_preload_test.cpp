// librebraid_preload.so under unmodified Embree programs: our client (preload_client/) and
// Embree's own tutorial programs (Debian's embree-tools). Each runs without and with the
// preload; what it prints and the image it writes must be the same, and the preload's log
// must say which scenes rebraid served and why Embree kept the others.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <ostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "support/cli_runner.h"

namespace rebraid::test {
namespace {

namespace fs = std::filesystem;

/// Runs `command` in `dir`/`run` with `environment` ("NAME=value ...") before it.
CommandResult run_program(const fs::path& dir, const std::string& run,
                          const std::string& environment, const std::string& command) {
    const fs::path run_dir = dir / run;
    fs::create_directories(run_dir);
    return run_shell_in(run_dir, "cd " + shell_quote(run_dir.string()) + " && timeout 300 env " +
                                     environment + " " + command);
}

std::string preload_environment(const std::string& more = "") {
    return "LD_PRELOAD=" + shell_quote(REBRAID_PRELOAD_LIBRARY) + " REBRAID_PRELOAD_LOG=1 " + more;
}

std::size_t count_lines_with(const std::string& text, const std::string& part) {
    std::size_t count = 0;
    for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1))
        ++count;
    return count;
}

std::string client_command(const std::string& arguments) {
    return shell_quote(REBRAID_PRELOAD_CLIENT) + " " + arguments;
}

TEST(EmbreePreload, ClientGetsEmbreesAnswersFromEveryRayQuery) {
    const fs::path dir = test_scratch_dir("embree_preload", true);
    const CommandResult embree = run_program(dir, "embree", "", client_command("trace"));
    const CommandResult preload =
        run_program(dir, "preload", preload_environment(), client_command("trace"));
    ASSERT_EQ(embree.exit_code, 0) << embree.err;
    ASSERT_EQ(preload.exit_code, 0) << preload.err;
    EXPECT_GT(count_lines_with(embree.out, " geom "), 1000u) << "the rays must hit something";
    EXPECT_TRUE(embree.out == preload.out) << "answers differ: see " << dir;
    // The served scene at each of its two commits; the scene it instances is never traced.
    EXPECT_EQ(count_lines_with(preload.err, "rebraid serves it"), 2u) << preload.err;
    EXPECT_EQ(count_lines_with(preload.err, "(updated: "), 1u) << preload.err;
    EXPECT_EQ(count_lines_with(preload.err, "Embree serves it"), 3u) << preload.err;
    EXPECT_NE(preload.err.find("RTC_GEOMETRY_TYPE_QUAD"), std::string::npos) << preload.err;
    EXPECT_NE(preload.err.find("filter"), std::string::npos) << preload.err;
    EXPECT_NE(preload.err.find("time step"), std::string::npos) << preload.err;
}

TEST(EmbreePreload, OffLeavesEverySceneToEmbreeSilently) {
    const fs::path dir = test_scratch_dir("embree_preload", true);
    const CommandResult embree = run_program(dir, "embree", "", client_command("trace"));
    const CommandResult off =
        run_program(dir, "off", preload_environment("REBRAID_PRELOAD=0"), client_command("trace"));
    ASSERT_EQ(off.exit_code, 0) << off.err;
    EXPECT_TRUE(embree.out == off.out);
    EXPECT_EQ(off.err, "");
}

TEST(EmbreePreload, BadSettingSaysSoOnceAndLeavesEverySceneToEmbree) {
    const fs::path dir = test_scratch_dir("embree_preload", true);
    const CommandResult embree = run_program(dir, "embree", "", client_command("trace"));
    const CommandResult bad = run_program(dir, "bad", preload_environment("REBRAID_PRELOAD=yes"),
                                          client_command("trace"));
    ASSERT_EQ(bad.exit_code, 0) << bad.err;
    EXPECT_TRUE(embree.out == bad.out);
    EXPECT_EQ(bad.err,
              "rebraid preload: REBRAID_PRELOAD=yes: expected 0 or 1; Embree serves every scene\n");
}

TEST(EmbreePreload, AccelSettingsFromTheEnvironmentGiveTheSameAnswers) {
    const fs::path dir = test_scratch_dir("embree_preload", true);
    const CommandResult embree = run_program(dir, "embree", "", client_command("trace"));
    // The last: variables set to the empty string, which read as unset.
    for (const char* settings :
         {"REBRAID_ACCEL=rebraid:opening=extent:bref-bounds=box",
          "REBRAID_ACCEL=rebraid:object-builder=embree-high:open-threshold=0.5",
          "REBRAID_ACCEL=rebraid:spatial-splits=0", "REBRAID_PRELOAD= REBRAID_ACCEL="}) {
        SCOPED_TRACE(settings);
        const CommandResult preload =
            run_program(dir, "preload", preload_environment(settings), client_command("trace"));
        ASSERT_EQ(preload.exit_code, 0) << preload.err;
        EXPECT_TRUE(embree.out == preload.out);
        EXPECT_EQ(count_lines_with(preload.err, "rebraid serves it"), 2u) << preload.err;
        EXPECT_EQ(preload.err.find("REBRAID_"), std::string::npos) << preload.err;
    }
}

TEST(EmbreePreload, BadAccelSettingSaysWhyAndLeavesEverySceneToEmbree) {
    const fs::path dir = test_scratch_dir("embree_preload", true);
    const CommandResult embree = run_program(dir, "embree", "", client_command("trace"));
    const CommandResult bad =
        run_program(dir, "bad", preload_environment("REBRAID_ACCEL=rebraid:opening=widest"),
                    client_command("trace"));
    ASSERT_EQ(bad.exit_code, 0) << bad.err;
    EXPECT_TRUE(embree.out == bad.out);
    EXPECT_EQ(bad.err,
              "rebraid preload: REBRAID_ACCEL=rebraid:opening=widest: accel "
              "'rebraid:opening=widest': opening=widest: valid values: extent, sah, overlap; "
              "Embree serves every scene\n");
    // The drop-in keeps every mesh in its object space, where Embree computes instance hits.
    const CommandResult world_space =
        run_program(dir, "world", preload_environment("REBRAID_ACCEL=rebraid:world-single=1"),
                    client_command("trace"));
    EXPECT_TRUE(embree.out == world_space.out);
    EXPECT_NE(world_space.err.find("world_space_copy_budget are not supported"), std::string::npos)
        << world_space.err;
    const CommandResult other = run_program(dir, "other", preload_environment("REBRAID_ACCEL=flat"),
                                            client_command("trace"));
    EXPECT_TRUE(embree.out == other.out);
    EXPECT_NE(other.err.find("REBRAID_ACCEL=flat: the preload builds rebraid only"),
              std::string::npos)
        << other.err;
}

TEST(EmbreePreload, ExportsEmbreesNamesOnly) {
    const fs::path dir = test_scratch_dir("embree_preload", true);
    const CommandResult symbols =
        run_program(dir, "nm", "", "nm -D --defined-only " + shell_quote(REBRAID_PRELOAD_LIBRARY));
    ASSERT_EQ(symbols.exit_code, 0) << symbols.err;
    std::size_t count = 0;
    std::istringstream lines(symbols.out);
    for (std::string line; std::getline(lines, line); ++count)
        EXPECT_NE(line.find(" rtc"), std::string::npos) << line;
    EXPECT_GT(count, 40u);
    EXPECT_NE(symbols.out.find(" rtcIntersect1\n"), std::string::npos);
    EXPECT_NE(symbols.out.find(" rtcOccludedNp\n"), std::string::npos);
}

/// The resident memory the client printed after `cycle` cycles, or -1.
long resident_after(const std::string& out, int cycle) {
    const std::string key = "cycle " + std::to_string(cycle) + ": resident ";
    const std::size_t at = out.find(key);
    return at == std::string::npos ? -1 : std::stol(out.substr(at + key.size()));
}

// Each cycle creates, commits, traces (so rebraid builds) and releases two scenes; what the
// preload built must go with them (Embree's scene included: the structure holds a reference).
TEST(MemoryEmbreePreload, CreateCommitTraceReleaseCyclesDoNotGrow) {
    const fs::path dir = test_scratch_dir("embree_preload", true);
    const CommandResult run =
        run_program(dir, "preload", "LD_PRELOAD=" + shell_quote(REBRAID_PRELOAD_LIBRARY),
                    client_command("cycles 3000"));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const long after_300 = resident_after(run.out, 300), after_3000 = resident_after(run.out, 3000);
    ASSERT_GT(after_300, 0) << run.out;
    ASSERT_GT(after_3000, 0) << run.out;
    // A leaked structure or scene costs tens of kB per cycle: 2,700 of them would be many MB.
    EXPECT_LT(after_3000 - after_300, 1024) << run.out;
}

// ---- Embree's tutorial programs -----------------------------------------------------------

/// One program of embree-tools, run with `arguments` without and with the preload.
struct TutorialRun {
    CommandResult embree;
    CommandResult preload;
    fs::path dir;
};

TutorialRun run_tutorial(const std::string& program, const std::string& arguments,
                         const std::string& preload_settings = "") {
    TutorialRun run;
    run.dir = test_scratch_dir("embree_preload", true);
    const std::string command = "/usr/bin/" + program + " " + arguments;
    run.embree = run_program(run.dir, "embree", "", command);
    run.preload = run_program(run.dir, "preload", preload_environment(preload_settings), command);
    return run;
}

bool has_tutorials(const std::string& program) {
    return fs::exists("/usr/bin/" + program);
}

#define REQUIRE_TUTORIAL(program)                                 \
    if (!has_tutorials(program))                                  \
    GTEST_SKIP() << "/usr/bin/" program                           \
                    " is missing: install Debian's embree-tools " \
                    "(scripts/install-deps.sh)"

/// The pixels of a binary PPM (P6, 8 bits), three bytes each; empty when unreadable.
std::string ppm_pixels(const fs::path& path, std::size_t& pixel_count) {
    const std::string file = read_text_file(path);
    std::istringstream header(file);
    std::string magic;
    std::size_t width = 0, height = 0, largest = 0;
    header >> magic >> width >> height >> largest;
    pixel_count = width * height;
    if (magic != "P6" || largest != 255 || file.size() < 3 * pixel_count) return {};
    return file.substr(file.size() - 3 * pixel_count);
}

/// Runs `program` writing image.ppm, and expects exit code 0 and the same image both times:
/// at most `ties` pixels may differ (documented ties: two surfaces hit at the same distance).
TutorialRun expect_same_image(const std::string& program, const std::string& arguments,
                              const std::string& preload_settings = "", std::size_t ties = 0) {
    TutorialRun run = run_tutorial(program, arguments + " -o image.ppm", preload_settings);
    EXPECT_EQ(run.embree.exit_code, 0) << run.embree.err;
    EXPECT_EQ(run.preload.exit_code, 0) << run.preload.err;
    std::size_t pixel_count = 0;
    const std::string embree_image = ppm_pixels(run.dir / "embree" / "image.ppm", pixel_count);
    const std::string preload_image = ppm_pixels(run.dir / "preload" / "image.ppm", pixel_count);
    EXPECT_GT(embree_image.size(), 1000u);
    EXPECT_EQ(embree_image.size(), preload_image.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i + 3 <= std::min(embree_image.size(), preload_image.size()); i += 3)
        differing += embree_image.compare(i, 3, preload_image, i, 3) != 0;
    EXPECT_LE(differing, ties) << "pixels differ: " << run.dir;
    return run;
}

TEST(EmbreeTools, MinimalPrintsTheSameHits) {
    REQUIRE_TUTORIAL("minimal");
    const TutorialRun run = run_tutorial("minimal", "");
    EXPECT_EQ(run.preload.exit_code, 0);
    EXPECT_NE(run.embree.out.find("Found intersection on geometry 0, primitive 0"),
              std::string::npos);
    EXPECT_EQ(run.embree.out, run.preload.out);
    EXPECT_EQ(count_lines_with(run.preload.err, "rebraid serves it"), 1u) << run.preload.err;
}

// 63 x 63: at an even width the middle column of pixels looks exactly along an edge of the
// cube, where two faces are hit at the same distance (a tie: Embree and rebraid may each
// report either face).
TEST(EmbreeTools, TriangleGeometryRendersTheSameImage) {
    REQUIRE_TUTORIAL("triangle_geometry");
    const TutorialRun run = expect_same_image("triangle_geometry", "--size 63 63");
    EXPECT_EQ(count_lines_with(run.preload.err, "rebraid serves it"), 1u) << run.preload.err;
}

TEST(EmbreeTools, InstancedGeometryRendersTheSameImage) {
    REQUIRE_TUTORIAL("instanced_geometry");
    const TutorialRun run = expect_same_image("instanced_geometry", "--size 63 63");
    EXPECT_GE(count_lines_with(run.preload.err, "rebraid serves it"), 1u) << run.preload.err;
    EXPECT_EQ(count_lines_with(run.preload.err, "Embree serves it"), 0u) << run.preload.err;
}

/// Exports `scene` with `rebraid export --embree-xml` into a folder of the running test;
/// returns the viewer's options for it (scene and camera).
std::string export_for_viewer(const std::string& scene) {
    const fs::path dir = test_scratch_dir("embree_preload_export", true);
    const CommandResult exported =
        run_rebraid_in(dir, {"export", scene, "--embree-xml", (dir / "xml").string()}, 300);
    EXPECT_EQ(exported.exit_code, 0) << exported.err;
    return "-i " + shell_quote((dir / "xml" / "scene.xml").string()) + " -c " +
           shell_quote((dir / "xml" / "camera.cfg").string());
}

/// The viewer (single rays) and viewer_stream (streams of rays) render the exported scene the
/// same with the preload, with the meshes flattened into one scene (`none`) and as one
/// Embree instance per instance over shared meshes (`geometry`).
void expect_viewers_render_the_same(const std::string& scene, const std::string& size,
                                    const std::string& expected_log, std::size_t ties = 0) {
    const std::string viewer_options = export_for_viewer(scene);
    for (const char* program : {"viewer", "viewer_stream"})
        for (const char* mode : {"none", "geometry"}) {
            SCOPED_TRACE(std::string(program) + " --instancing " + mode);
            const TutorialRun run = expect_same_image(
                program, viewer_options + " --instancing " + mode + " --size " + size, "", ties);
            EXPECT_EQ(count_lines_with(run.preload.err, "rebraid serves it"), 1u)
                << run.preload.err;
            EXPECT_NE(run.preload.err.find(expected_log), std::string::npos) << run.preload.err;
        }
}

TEST(EmbreeTools, ViewersRenderAnExportedSceneOfOverlappingInstancesTheSame) {
    REQUIRE_TUTORIAL("viewer");
    const fs::path dir = test_scratch_dir("embree_preload_scene", true);
    const std::string scene = (dir / "trees.glb").string();
    const CommandResult generated =
        run_rebraid_in(dir, {"generate", "trees", "--instances", "12", "-o", scene}, 300);
    ASSERT_EQ(generated.exit_code, 0) << generated.err;
    expect_viewers_render_the_same(scene, "64 48", "12 instances, 29824 triangles");
}

// The shared scenes whose instances overlap (half a minute or so in all). Brainstem's meshes
// hold coincident surfaces: at 2 of its 57,600 pixels two triangles are hit at the same
// distance (a tie), and Embree and rebraid each report one of them.
TEST(SlowEmbreeTools, ViewersRenderTheExportedSharedScenesTheSame) {
    REQUIRE_TUTORIAL("viewer");
    const std::pair<const char*, std::size_t> scenes[] = {
        {"two_cylinder_engine", 0}, {"brainstem", 2}, {"cg57_cruiser", 0}};
    for (const auto& [name, ties] : scenes) {
        SCOPED_TRACE(name);
        const fs::path scene = fs::path(REBRAID_SHARED_SCENES) / (std::string(name) + ".glb");
        if (!fs::exists(scene)) GTEST_SKIP() << scene << " is missing";
        expect_viewers_render_the_same(scene.string(), "320 180", "rebraid serves it", ties);
    }
}

/// A program whose scenes the preload must leave to Embree, and a part of the reason the
/// log gives.
struct LeftToEmbree {
    const char* program;
    const char* reason;
};

// Names the parameter in test listings (ctest shows it).
void PrintTo(const LeftToEmbree& expected, std::ostream* out) {
    *out << expected.program;
}

class EmbreeToolsLeftToEmbree : public ::testing::TestWithParam<LeftToEmbree> {};

TEST_P(EmbreeToolsLeftToEmbree, RendersTheSameImageAndTheLogSaysWhy) {
    const LeftToEmbree& expected = GetParam();
    if (!has_tutorials(expected.program)) GTEST_SKIP() << expected.program << " is missing";
    const TutorialRun run = expect_same_image(expected.program, "--size 63 63");
    EXPECT_GE(count_lines_with(run.preload.err, "Embree serves it"), 1u) << run.preload.err;
    EXPECT_NE(run.preload.err.find(expected.reason), std::string::npos) << run.preload.err;
}

// user_geometry instances scenes of triangles through its own user geometry; those nested
// queries carry the instance on the context's stack and go to Embree too. lazy_geometry
// builds and commits scenes from inside its intersect function while other threads trace
// (rebraid serves those inner scenes; its user geometry stays with Embree).
INSTANTIATE_TEST_SUITE_P(Tutorials, EmbreeToolsLeftToEmbree,
                         ::testing::Values(LeftToEmbree{"user_geometry", "RTC_GEOMETRY_TYPE_USER"},
                                           LeftToEmbree{"lazy_geometry", "RTC_GEOMETRY_TYPE_USER"},
                                           LeftToEmbree{"intersection_filter", "filter function"},
                                           LeftToEmbree{"motion_blur_geometry", "motion blur"},
                                           LeftToEmbree{"curve_geometry", "curve geometry"},
                                           LeftToEmbree{"dynamic_scene", "RTC_SCENE_FLAG_ROBUST"}),
                         [](const ::testing::TestParamInfo<LeftToEmbree>& info) {
                             return std::string(info.param.program);
                         });

}  // namespace
}  // namespace rebraid::test
