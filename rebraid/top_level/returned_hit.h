#pragma once

// Kernel header: included by trace_kernel_bodies.h, after simd_config.h chose the level.

#include <bit>
#include <cstddef>

#include "rebraid/core/ray.h"
#include "rebraid/core/simd_config.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// `hit` as a query's entry point hands it back: in the SIMD kernels written with one 16-byte
/// store of t, instance_id, prim_id and u, and one of v.
///
/// A Hit (20 bytes) is returned in memory, and a caller that copies it (`hits[i] =
/// accel.intersect(ray)`) reads it back at once with a 16-byte load and a 4-byte one. Built
/// field by field, as the traversal builds it, the 16-byte load spans several smaller stores,
/// which the CPU cannot forward to it: the load waits until they reach the cache, on every
/// ray. Where rays are cheap (most miss, or end after a node or two) the wait shows:
/// motion_capture_rom's primary rays traced 1.05x (`rebraid`) and 1.07x (`flat`) as fast
/// with the hit handed back this way (docs/design.md, "Handing the hit back"). A field read
/// on its own is served from within the 16-byte store too.
inline Hit returned_hit(const Hit& hit) {
#ifdef REBRAID_SIMD_AVX2
    static_assert(sizeof(Hit) == 20 && offsetof(Hit, u) == 12 && offsetof(Hit, v) == 16);
    Hit out;
    // Each field is read alone (each load is served by the store that wrote it), then the
    // four are stored at once.
    const __m128 head = _mm_setr_ps(hit.t, std::bit_cast<float>(hit.instance_id),
                                    std::bit_cast<float>(hit.prim_id), hit.u);
    _mm_storeu_ps(reinterpret_cast<float*>(&out), head);
    out.v = hit.v;
    return out;
#else
    return hit;
#endif
}

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
