#pragma once

// Which SIMD kernels the traversal headers compile to, from the compiler's target flags at
// their first inclusion in a translation unit (CMake option REBRAID_AVX2 adds -mavx2 -mfma to
// the library). Two macros, defined before that inclusion, change the choice:
// REBRAID_SIMD_FORCE_PORTABLE picks the portable kernels whatever the flags (the portable
// kernel unit of an AVX2 build); REBRAID_SIMD_TARGET_AVX512 names the AVX-512 kernels, for the
// unit that compiles them under `#pragma GCC target` or clang's `#pragma clang attribute`
// (which do not define the ISA macros).
#if defined(__AVX2__) && defined(__FMA__) && !defined(REBRAID_SIMD_FORCE_PORTABLE)
#include <immintrin.h>
#define REBRAID_SIMD_AVX2 1
#if defined(REBRAID_SIMD_TARGET_AVX512)
/// The AVX2 kernels, compiled with AVX-512's 32 registers and mask compares.
#define REBRAID_SIMD_AVX512 1
#define REBRAID_SIMD_NAMESPACE simd_avx512
#else
/// Inline namespace of the kernels: it puts the instruction set into every mangled name, so
/// a translation unit built for another level (a test, a user's file, the other kernel units)
/// that includes the traversal headers gets its own copies instead of silently sharing (and
/// mixing up, since some types differ) these at link time.
#define REBRAID_SIMD_NAMESPACE simd_avx2
#endif
#else
#define REBRAID_SIMD_NAMESPACE simd_portable
#endif
