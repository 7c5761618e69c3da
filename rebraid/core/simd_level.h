#pragma once

#include <optional>
#include <string_view>
#include <vector>

namespace rebraid {

/// The instruction sets the traversal kernels are compiled for. A build holds the portable
/// kernels always, and on x86-64 with the REBRAID_AVX2 option (the default) the AVX2 ones and,
/// with GCC, the AVX-512 ones too; each structure picks one at run time (default_simd_level()).
/// Every level gives the same hits.
enum class SimdLevel {
    portable,  ///< scalar code, any CPU
    avx2,      ///< 8-wide AVX2 + FMA
    avx512,    ///< the AVX2 kernels compiled for AVX-512 (F, VL, BW, DQ): 32 vector registers
};

/// "portable", "avx2" or "avx512".
std::string_view simd_level_name(SimdLevel level);

/// The level of a name simd_level_name() gives, or nothing.
std::optional<SimdLevel> parse_simd_level(std::string_view name);

/// Levels this build holds kernels for and this CPU (and OS) can run, lowest first.
std::vector<SimdLevel> runnable_simd_levels();

/// True when runnable_simd_levels() holds `level`.
bool is_simd_level_runnable(SimdLevel level);

/// The level structures use unless told otherwise: the environment variable REBRAID_SIMD when
/// set (a name above, to compare or to rule out a kernel), else the highest runnable level.
/// Throws rebraid::Error naming the value when REBRAID_SIMD names no level or one that cannot
/// run here.
SimdLevel default_simd_level();

}  // namespace rebraid
