#pragma once

// Which kernel levels (simd_level.h) this build compiles. Included only by the library's own
// .cpp files, which all share the project's SIMD flags, so every one sees the same answer.

#if defined(__x86_64__) && defined(__AVX2__) && defined(__FMA__)
#define REBRAID_KERNELS_AVX2 1
// The AVX-512 kernels are the AVX2 sources compiled with AVX-512 enabled for their functions
// (`#pragma GCC target`, or clang's `#pragma clang attribute`).
#define REBRAID_KERNELS_AVX512 1
#endif
