#pragma once

// Which kernel levels (simd_level.h) this build compiles. Included only by the library's own
// .cpp files, which all share the project's SIMD flags, so every one sees the same answer.

#if defined(__x86_64__) && defined(__AVX2__) && defined(__FMA__)
#define REBRAID_KERNELS_AVX2 1
// The AVX-512 kernels are the AVX2 sources compiled under `#pragma GCC target`, which also
// defines the ISA macros simd_config.h reads; clang has no such pragma.
#if defined(__GNUC__) && !defined(__clang__)
#define REBRAID_KERNELS_AVX512 1
#endif
#endif
