#include "rebraid/core/simd_level.h"

#include <algorithm>
#include <cstdlib>
#include <string>

#include "rebraid/core/error.h"
#include "rebraid/core/simd_kernels_built.h"

namespace rebraid {

std::string_view simd_level_name(SimdLevel level) {
    switch (level) {
        case SimdLevel::portable:
            return "portable";
        case SimdLevel::avx2:
            return "avx2";
        case SimdLevel::avx512:
            return "avx512";
    }
    return "unknown";
}

std::optional<SimdLevel> parse_simd_level(std::string_view name) {
    for (SimdLevel level : {SimdLevel::portable, SimdLevel::avx2, SimdLevel::avx512})
        if (name == simd_level_name(level)) return level;
    return std::nullopt;
}

std::vector<SimdLevel> runnable_simd_levels() {
    std::vector<SimdLevel> levels{SimdLevel::portable};
#ifdef REBRAID_KERNELS_AVX2
    // __builtin_cpu_supports also asks the OS (XGETBV) whether it saves the wide registers.
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        levels.push_back(SimdLevel::avx2);
#endif
#ifdef REBRAID_KERNELS_AVX512
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
        __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq"))
        levels.push_back(SimdLevel::avx512);
#endif
    return levels;
}

bool is_simd_level_runnable(SimdLevel level) {
    const std::vector<SimdLevel> levels = runnable_simd_levels();
    return std::find(levels.begin(), levels.end(), level) != levels.end();
}

SimdLevel default_simd_level() {
    const std::vector<SimdLevel> levels = runnable_simd_levels();
    const char* requested = std::getenv("REBRAID_SIMD");
    if (requested == nullptr || *requested == '\0') return levels.back();
    std::string runnable;
    for (SimdLevel level : levels)
        runnable += (runnable.empty() ? "" : ", ") + std::string(simd_level_name(level));
    const std::optional<SimdLevel> level = parse_simd_level(requested);
    if (!level)
        throw Error("REBRAID_SIMD=" + std::string(requested) +
                    " names no kernel level; runnable here: " + runnable);
    if (!is_simd_level_runnable(*level))
        throw Error("REBRAID_SIMD=" + std::string(requested) +
                    ": this build or this CPU cannot run it; runnable here: " + runnable);
    return *level;
}

}  // namespace rebraid
