#pragma once

#include "rebraid/bvh/node_box_test.h"
#include "rebraid/bvh/traversal_ray.h"
#include "rebraid/bvh/triangle_group.h"
#include "rebraid/core/simd_config.h"
#include "rebraid/core/types.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// A ray made ready for traversal in one space: the scalar ray plus the values the box and
/// triangle kernels broadcast from it. Made once per ray and per instance space and shared by
/// every traversal in that space, so that entering an object BVH (a re-braided top level
/// enters several per ray, mostly in the same space) costs no set-up beyond the call.
/// Not copyable: the portable box test refers to `ray`.
struct PreparedRay {
    TraversalRay ray;
    NodeBoxTest box_test;
    TriangleGroupRay triangle_ray;

    PreparedRay(Vec3f origin, Vec3f direction, float tnear, float tfar)
        : ray(origin, direction, tnear, tfar), box_test(ray), triangle_ray(origin, direction) {}
    /// With the slab terms of `origin` and `direction` already made.
    PreparedRay(Vec3f origin, Vec3f direction, float tnear, float tfar, const SlabTerms& slab_terms)
        : ray(origin, direction, tnear, tfar, slab_terms),
          box_test(ray),
          triangle_ray(origin, direction) {}
    PreparedRay(const PreparedRay&) = delete;
    PreparedRay& operator=(const PreparedRay&) = delete;
};

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
