#pragma once

// Every header the trace kernels (trace_kernel_bodies.h) use, except the kernel headers
// themselves. The AVX-512 kernel unit includes this before it switches the target to AVX-512,
// so that no function outside the kernels' ISA namespace is compiled for AVX-512: such a
// function (an inline or template from a shared header) could otherwise be the copy the
// linker keeps for the whole program, and fault on a CPU without AVX-512.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/transform.h"
#include "rebraid/core/triangle.h"
#include "rebraid/core/types.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instance_target.h"
#include "rebraid/top_level/instanced_accel.h"
#include "rebraid/top_level/merged_top_level.h"
#include "rebraid/top_level/top_level_bvh.h"
#include "rebraid/top_level/trace_kernels.h"
