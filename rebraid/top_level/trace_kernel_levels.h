#pragma once

#include "rebraid/top_level/trace_kernels.h"

namespace rebraid {

// The kernel table of each level, one per trace_kernels_<level>.cpp; a level this build does
// not compile (rebraid/core/simd_kernels_built.h) has no definition and is never called.
const TraceKernels& portable_trace_kernels(TriangleTest test);
const TraceKernels& avx2_trace_kernels(TriangleTest test);
const TraceKernels& avx512_trace_kernels(TriangleTest test);

}  // namespace rebraid
