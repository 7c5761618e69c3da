#pragma once

#include <limits>

#include "rebraid/core/types.h"

namespace rebraid {

/// A ray segment org + t * dir, t in [tnear, tfar]. `dir` need not be normalized: t is in
/// units of dir, as in Embree, so t is unchanged by affine maps of the ray.
struct Ray {
    Vec3f org;
    float tnear = 0.0f;
    Vec3f dir;
    float tfar = std::numeric_limits<float>::infinity();
};

/// Closest hit. A miss has t = +inf and both ids kInvalidId.
struct Hit {
    float t = std::numeric_limits<float>::infinity();
    InstanceId instance_id = kInvalidId;
    PrimId prim_id = kInvalidId;
    float u = 0.0f;  ///< barycentric weight of vertex 1 (Embree's convention)
    float v = 0.0f;  ///< barycentric weight of vertex 2
    bool is_hit() const { return prim_id != kInvalidId; }
};

}  // namespace rebraid
