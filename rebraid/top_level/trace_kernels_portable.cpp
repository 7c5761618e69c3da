// The portable kernels: built in every configuration (in an AVX2 build as well, so that tests
// can compare every level on one machine).
#define REBRAID_SIMD_FORCE_PORTABLE 1
#include "rebraid/top_level/trace_kernel_bodies.h"
#include "rebraid/top_level/trace_kernel_levels.h"

namespace rebraid {

const TraceKernels& portable_trace_kernels(TriangleTest test) {
    return simd_portable::level_trace_kernels(test);
}

}  // namespace rebraid
