// Bounded memory: the two-level structures build a scene of more than 100 M
// instanced triangles under an address-space limit (prlimit --as) far below what flattening
// it would need, `rebraid stats --json` reports the peak resident memory, and the BRef array
// stays within a documented cap whatever --budget-factor asks for.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/error.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/bref_budget.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "support/reachability.h"
#include "support/test_scenes.h"

// Sanitizers reserve terabytes of shadow address space, so an address-space limit cannot
// work under them (docs/testing.md).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define REBRAID_UNDER_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define REBRAID_UNDER_SANITIZER 1
#endif
#endif

namespace rebraid {
namespace {

namespace fs = std::filesystem;

/// Address-space limit for the two-level builds of the huge scene. It covers the scene
/// (about 60 k distinct triangles), object BVHs, the top level, and the address space the
/// process maps anyway (shared libraries, TBB worker stacks, malloc arenas). Measured peak
/// resident memory: about 150 MiB (docs/testing.md).
constexpr std::uint64_t kTwoLevelAddressLimit = std::uint64_t(1) << 30;  // 1 GiB

/// Limit for the re-braided build with --budget-factor 1e6: the capped BRef array (2^22 extra
/// BRefs), its build scratch (allocated once for the whole build rather than per partition,
/// which is why it is 2 GiB and not the 1.5 GiB of a build that allocated per partition) and
/// the top level. Measured peak resident memory: about 1.1 GiB. Uncapped, the array alone
/// would need over 5 GiB.
constexpr std::uint64_t kHugeBudgetAddressLimit = std::uint64_t(1) << 31;  // 2 GiB

/// Bytes a flat structure must at least hold per instanced triangle, counting only its
/// output (no BVH nodes, no build scratch): three world-space float corners (36 bytes) and
/// the instance and primitive id that answer a hit (8 bytes).
constexpr std::uint64_t kFlatBytesPerTriangle = 36 + 8;

struct CommandResult {
    int exit_code = -1;  ///< -1: killed by a signal
    std::string out;
    std::string err;
};

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

/// Runs `command` (already shell-quoted) with its output in files of this test.
CommandResult run(const std::string& command) {
    const fs::path dir = fs::path(REBRAID_TEST_TMP) / "memory_limit_test";
    fs::create_directories(dir);
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::string stem = (dir / info->name()).string();
    const int status = std::system((command + " >'" + stem + ".out' 2>'" + stem + ".err'").c_str());
    CommandResult result;
    result.exit_code = (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
    result.out = read_text(stem + ".out");
    result.err = read_text(stem + ".err");
    return result;
}

/// `rebraid ARGS` on two threads under an address-space limit of `limit` bytes. The thread
/// count is pinned: every TBB worker maps a stack and a malloc arena, so the address space a
/// build needs grows with the cores of the machine, and the limits are set for two.
std::string limited_rebraid(std::uint64_t limit, const std::string& arguments) {
    return "prlimit --as=" + std::to_string(limit) + " '" + std::string(REBRAID_CLI) + "' " +
           arguments + " --threads 2";
}

/// The huge generated scene (12,000 instances, about 176 M instanced triangles), written
/// once per test (ctest runs tests in parallel processes: one file each).
const std::string& huge_scene_path() {
    static const std::string path = [] {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        const std::string file = std::string(REBRAID_TEST_TMP) + "/memory_limit_test_huge_" +
                                 info->test_suite_name() + "." + info->name() + ".glb";
        const CommandResult generated =
            run("'" + std::string(REBRAID_CLI) + "' generate huge -o '" + file + "'");
        EXPECT_EQ(generated.exit_code, 0) << generated.err;
        return file;
    }();
    return path;
}

// About 25 s on two shared cores: in the default suite.
TEST(BoundedMemory, TwoLevelAndRebraidBuildHugeSceneFarBelowFlatMemory) {
#ifdef REBRAID_UNDER_SANITIZER
    GTEST_SKIP() << "address-space limits do not work under sanitizers";
#endif
    const Scene scene = load_gltf_scene(huge_scene_path());
    const std::uint64_t instanced = scene.instanced_triangle_count();
    ASSERT_GE(instanced, 100'000'000u) << "the scene must hold at least 100 M triangles";
    const std::uint64_t flat_lower_bound = instanced * kFlatBytesPerTriangle;
    const double ratio = double(flat_lower_bound) / double(kTwoLevelAddressLimit);
    std::cout << "[ memory   ] " << instanced << " instanced triangles, "
              << scene.mesh_triangle_count() << " distinct; flat needs at least "
              << flat_lower_bound / (1u << 20) << " MiB; limit "
              << kTwoLevelAddressLimit / (1u << 20) << " MiB (" << ratio << "x less)\n";
    EXPECT_GE(ratio, 5.0);

    for (const char* accel : {"twolevel", "rebraid"}) {
        const CommandResult result = run(limited_rebraid(
            kTwoLevelAddressLimit, "stats '" + huge_scene_path() + "' --json --accel " + accel));
        ASSERT_EQ(result.exit_code, 0) << accel << ": " << result.err;
        const nlohmann::json json = nlohmann::json::parse(result.out);
        EXPECT_EQ(json.at("triangles").get<std::uint64_t>(), instanced) << accel;
        const std::uint64_t peak = json.at("peak_rss_bytes").get<std::uint64_t>();
        std::cout << "[ memory   ] " << accel << ": peak resident " << peak / (1u << 20)
                  << " MiB, structure " << json.at("memory_bytes").get<std::uint64_t>() / (1u << 20)
                  << " MiB, build " << json.at("build_ms").get<double>() << " ms\n";
        EXPECT_GT(peak, json.at("memory_bytes").get<std::uint64_t>()) << accel;
        EXPECT_LT(peak, kTwoLevelAddressLimit) << accel;
    }
    // The limit is real: flattening the same scene under it fails, cleanly.
    const CommandResult flat = run(limited_rebraid(
        kTwoLevelAddressLimit, "stats '" + huge_scene_path() + "' --json --accel flat"));
    EXPECT_EQ(flat.exit_code, 1) << flat.err;
}

// About 40 s (the re-braided build opens 600 k BRefs): label `memory` (suites named Memory*).
TEST(MemoryBudget, HugeBudgetFactorStaysWithinTheCap) {
#ifdef REBRAID_UNDER_SANITIZER
    GTEST_SKIP() << "address-space limits do not work under sanitizers";
#endif
    // --budget-factor 1e6 on 12,000 instances asks for 1.2e10 extra BRefs; the cap
    // (RebraidSettings::max_budget) keeps the array at 2^22 and the build under the limit
    // (without the cap: 2^27 BRefs, over 5 GiB).
    const CommandResult result =
        run(limited_rebraid(kHugeBudgetAddressLimit, "stats '" + huge_scene_path() +
                                                         "' --json --accel rebraid "
                                                         "--budget-factor 1e6"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json json = nlohmann::json::parse(result.out);
    EXPECT_EQ(json.at("budget").get<std::uint64_t>(), RebraidSettings{}.max_budget);
    EXPECT_LE(json.at("brefs").get<std::uint64_t>(),
              json.at("instances").get<std::uint64_t>() + RebraidSettings{}.max_budget);
}

TEST(BRefBudget, IsCappedByPrimitivesAndMaxBudget) {
    const RebraidSettings huge{.budget_factor = 1e6f};
    // The rule alone: 1e6 x 1,000 instances.
    EXPECT_EQ(bref_budget(huge, 1000, std::uint64_t(1) << 40), huge.max_budget);
    // Opening cannot make more BRefs than primitives.
    EXPECT_EQ(bref_budget(huge, 1000, 5000), 4000u);
    EXPECT_EQ(bref_budget(huge, 1000, 1000), 0u);
    EXPECT_EQ(bref_budget({.budget_factor = 2.0f}, 1000, 1u << 20), 2000u);  // uncapped
    RebraidSettings small_cap{.budget_factor = 4.0f};
    small_cap.max_budget = 100;
    EXPECT_EQ(bref_budget(small_cap, 1000, 1u << 20), 100u);
    const RebraidSettings per_primitive{.budget_rule = BudgetRule::per_primitive,
                                        .primitives_per_bref = 1.0f};
    EXPECT_EQ(bref_budget(per_primitive, 10, 100), 90u);
    // The default takes the larger of 4 per instance and one per 1,000 primitives.
    EXPECT_EQ(bref_budget({}, 10, 1'000'000), 1000u);
    EXPECT_EQ(bref_budget({}, 1000, 1'000'000), 4000u);
    EXPECT_EQ(bref_budget({.budget_factor = 0.0f}, 1000, 1'000'000), 1000u);
}

TEST(BRefBudget, MaxBudgetAboveTheItemLimitIsRejected) {
    RebraidSettings settings;
    settings.max_budget = std::uint64_t(1) << 27;
    EXPECT_THROW(settings.validate(), Error);
    settings.max_budget = (std::uint64_t(1) << 27) - 1;
    EXPECT_NO_THROW(settings.validate());
}

TEST(BRefBudget, HugeFactorBuildKeepsItsBudgetAndReachesEveryTriangle) {
    const Scene scene = test::make_overlap_scene(60, 5);
    const std::vector<ObjectBvh> bvhs = build_object_bvhs(scene, own_object_bvh_builder());
    RebraidBuild build =
        build_rebraid(scene, bvhs, {.open_threshold = 0.0f, .budget_factor = 1e6f});
    const std::uint64_t instances = scene.instances.size();
    // At most a BRef per triangle reference (a triangle cut by spatial splits has several).
    std::uint64_t references = 0;
    for (const Instance& instance : scene.instances)
        references += bvhs[instance.mesh_id].prim_count();
    EXPECT_LE(build.budget, references - instances);
    EXPECT_LE(build.brefs, instances + build.budget);
    EXPECT_GT(build.opened, 0u);
    const InstancedAccel accel(scene, bvhs, std::move(build.top), {});
    test::expect_each_reached_once(test::reach_counts(scene, accel));
}

}  // namespace
}  // namespace rebraid
