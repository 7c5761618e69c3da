#include "rebraid/core/simd_level.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <string>

#include "rebraid/core/error.h"

namespace rebraid {
namespace {

/// Sets REBRAID_SIMD for the scope of a test, then restores it.
class ScopedSimdVariable {
public:
    explicit ScopedSimdVariable(const char* value) {
        if (const char* old = std::getenv("REBRAID_SIMD")) old_ = old;
        setenv("REBRAID_SIMD", value, 1);
    }
    ~ScopedSimdVariable() {
        if (old_.empty())
            unsetenv("REBRAID_SIMD");
        else
            setenv("REBRAID_SIMD", old_.c_str(), 1);
    }

private:
    std::string old_;
};

TEST(SimdLevel, NamesParseBackAndUnknownNamesDoNot) {
    for (SimdLevel level : {SimdLevel::portable, SimdLevel::avx2, SimdLevel::avx512})
        EXPECT_EQ(parse_simd_level(simd_level_name(level)), level);
    EXPECT_FALSE(parse_simd_level("sse4"));
    EXPECT_FALSE(parse_simd_level(""));
    EXPECT_FALSE(parse_simd_level("AVX2"));
}

TEST(SimdLevel, PortableAlwaysRunsAndLevelsComeLowestFirst) {
    const std::vector<SimdLevel> levels = runnable_simd_levels();
    ASSERT_FALSE(levels.empty());
    EXPECT_EQ(levels.front(), SimdLevel::portable);
    EXPECT_TRUE(std::is_sorted(levels.begin(), levels.end()));
}

#ifdef REBRAID_TEST_AVX2_BUILD
// A build with the REBRAID_AVX2 option (the default) must hold the kernels this CPU can run:
// a build step that lost them would leave every structure on slower kernels, silently.
TEST(SimdLevel, AnAvx2BuildRunsTheWidestKernelsTheCpuHas) {
    EXPECT_EQ(is_simd_level_runnable(SimdLevel::avx2),
              __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"));
#ifdef REBRAID_TEST_AVX512_BUILD
    const bool cpu_has_avx512 =
        __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
        __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq");
    EXPECT_EQ(is_simd_level_runnable(SimdLevel::avx512), cpu_has_avx512);
#endif
}
#endif

TEST(SimdLevel, DefaultIsTheHighestRunnableLevelUnlessTheEnvironmentNamesOne) {
    {
        const ScopedSimdVariable unset("");
        EXPECT_EQ(default_simd_level(), runnable_simd_levels().back());
    }
    for (SimdLevel level : runnable_simd_levels()) {
        const ScopedSimdVariable named(std::string(simd_level_name(level)).c_str());
        EXPECT_EQ(default_simd_level(), level);
    }
}

TEST(SimdLevel, UnknownOrUnrunnableEnvironmentValuesAreClearErrors) {
    const ScopedSimdVariable named("sse9");
    try {
        default_simd_level();
        FAIL() << "REBRAID_SIMD=sse9 was accepted";
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find("REBRAID_SIMD=sse9"), std::string::npos) << message;
        EXPECT_NE(message.find("portable"), std::string::npos) << message;
    }
    for (SimdLevel level : {SimdLevel::avx2, SimdLevel::avx512}) {
        if (is_simd_level_runnable(level)) continue;
        const ScopedSimdVariable unrunnable(std::string(simd_level_name(level)).c_str());
        EXPECT_THROW(default_simd_level(), Error) << simd_level_name(level);
    }
}

}  // namespace
}  // namespace rebraid
