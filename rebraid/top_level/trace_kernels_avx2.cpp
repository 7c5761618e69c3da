// The AVX2 kernels: the library's own compiler flags (-mavx2 -mfma) select them.
#include "rebraid/core/simd_kernels_built.h"

#ifdef REBRAID_KERNELS_AVX2
#include "rebraid/top_level/trace_kernel_bodies.h"
#include "rebraid/top_level/trace_kernel_levels.h"

namespace rebraid {

const TraceKernels& avx2_trace_kernels(TriangleTest test) {
    return simd_avx2::level_trace_kernels(test);
}

}  // namespace rebraid
#endif
