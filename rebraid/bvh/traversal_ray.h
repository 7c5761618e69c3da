#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/simd_config.h"
#include "rebraid/core/types.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// Byte offset inside a WideNode of the plane array of `axis` a ray enters boxes through
/// (`is_far` false) or leaves them through (true), for a direction of sign `is_negative`
/// along that axis: the lower planes first for a positive direction, the upper ones for a
/// negative one.
constexpr std::uint32_t slab_plane_offset(int axis, bool is_negative, bool is_far) {
    // WideNode stores each axis's lower plane array followed by its upper one.
    static_assert(offsetof(WideNode, upper_x) == offsetof(WideNode, lower_x) + 32 &&
                  offsetof(WideNode, lower_y) == offsetof(WideNode, lower_x) + 64 &&
                  offsetof(WideNode, upper_y) == offsetof(WideNode, lower_x) + 96 &&
                  offsetof(WideNode, lower_z) == offsetof(WideNode, lower_x) + 128 &&
                  offsetof(WideNode, upper_z) == offsetof(WideNode, lower_x) + 160);
    const bool is_upper = is_negative != is_far;
    return std::uint32_t(offsetof(WideNode, lower_x)) + 64u * std::uint32_t(axis) +
           32u * std::uint32_t(is_upper);
}

/// A ray prepared for box tests: reciprocal direction with zero components replaced by tiny
/// ones (so no 0 * inf appears) and, per axis, the byte offsets inside a WideNode of the
/// plane arrays the ray enters (near) and leaves (far) a box through.
struct TraversalRay {
    Vec3f org;
    Vec3f dir;
    Vec3f rdir;
    float tnear = 0.0f;
    float tfar = 0.0f;
    std::uint32_t near_offset[3] = {};
    std::uint32_t far_offset[3] = {};

    TraversalRay(Vec3f origin, Vec3f direction, float t_near, float t_far)
        : org(origin), dir(direction), tnear(t_near), tfar(t_far) {
        for (int a = 0; a < 3; ++a) {
            const float d = direction[a];
            const float safe = std::fabs(d) < 1e-18f ? std::copysign(1e-18f, d) : d;
            rdir[a] = 1.0f / safe;
            const bool is_negative = !(rdir[a] >= 0.0f);
            near_offset[a] = slab_plane_offset(a, is_negative, false);
            far_offset[a] = slab_plane_offset(a, is_negative, true);
        }
    }
};

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
