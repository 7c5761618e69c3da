#pragma once

// Which SIMD kernels the traversal headers compile to, from the compiler's target flags
// (CMake option REBRAID_AVX2 adds -mavx2 -mfma to the core library).
#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#define REBRAID_SIMD_AVX2 1
/// Inline namespace of the kernels: it puts the instruction set into every mangled name, so
/// a translation unit built without AVX2 (a test, a user's file) that includes the traversal
/// headers gets its own portable copies instead of silently sharing (and mixing up, since
/// some types differ) the AVX2 ones at link time.
#define REBRAID_SIMD_NAMESPACE simd_avx2
#else
#define REBRAID_SIMD_NAMESPACE simd_portable
#endif
