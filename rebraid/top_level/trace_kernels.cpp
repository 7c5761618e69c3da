#include "rebraid/top_level/trace_kernels.h"

#include <string>

#include "rebraid/core/error.h"
#include "rebraid/core/simd_kernels_built.h"
#include "rebraid/top_level/trace_kernel_levels.h"

namespace rebraid {

const TraceKernels& trace_kernels(SimdLevel level, TriangleTest test) {
    if (!is_simd_level_runnable(level))
        throw Error("kernel level " + std::string(simd_level_name(level)) +
                    " cannot run here: this build or this CPU lacks it");
    switch (level) {
#ifdef REBRAID_KERNELS_AVX512
        case SimdLevel::avx512:
            return avx512_trace_kernels(test);
#endif
#ifdef REBRAID_KERNELS_AVX2
        case SimdLevel::avx2:
            return avx2_trace_kernels(test);
#endif
        default:
            return portable_trace_kernels(test);
    }
}

}  // namespace rebraid
