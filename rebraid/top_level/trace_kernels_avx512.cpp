// The AVX-512 kernels: the AVX2 sources compiled for AVX-512 (F, VL, BW, DQ), which gives the
// compiler 32 vector registers (the triangle test spills with 16) and mask compares.
#include "rebraid/core/simd_kernels_built.h"

#ifdef REBRAID_KERNELS_AVX512
// Every shared header first, compiled for the library's own target (see the prelude).
#include "rebraid/top_level/trace_kernel_levels.h"
#include "rebraid/top_level/trace_kernel_prelude.h"

#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))), \
                             apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx512f,avx512vl,avx512bw,avx512dq")
#endif
#define REBRAID_SIMD_TARGET_AVX512 1
#include "rebraid/top_level/trace_kernel_bodies.h"
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

namespace rebraid {

const TraceKernels& avx512_trace_kernels(TriangleTest test) {
    return simd_avx512::level_trace_kernels(test);
}

}  // namespace rebraid
#endif
