#pragma once

#include "rebraid/object_bvh.h"
#include "rebraid/traversal.h"
#include "rebraid/triangle.h"

namespace rebraid {

/// Closest hit among the triangles below `start` (any node of `bvh`), for a ray already in
/// the BVH's space. On a closer hit sets ray.tfar and hit.t/u/v/prim_id (mesh primID) and
/// returns true; leaves hit.instance_id to the caller.
inline bool intersect_object_bvh(const ObjectBvh& bvh, NodeRef start, TraversalRay& ray, Hit& hit,
                                 TraversalCounters* counters) {
    bool found = false;
    traverse_bvh(bvh.nodes.data(), start, ray, counters, [&](NodeRef leaf) {
        const std::uint32_t end = leaf.first_prim() + leaf.prim_count();
        for (std::uint32_t i = leaf.first_prim(); i < end; ++i) {
            float t, u, v;
            if (intersect_triangle(bvh.triangles[i], ray.org, ray.dir, ray.tnear, ray.tfar, t, u,
                                   v)) {
                ray.tfar = t;
                hit.t = t;
                hit.u = u;
                hit.v = v;
                hit.prim_id = bvh.prim_ids[i];
                found = true;
            }
        }
        if (counters) counters->triangles_tested += leaf.prim_count();
        return false;
    });
    return found;
}

/// True when any triangle below `start` is hit within [ray.tnear, ray.tfar].
inline bool occluded_object_bvh(const ObjectBvh& bvh, NodeRef start, TraversalRay& ray,
                                TraversalCounters* counters) {
    return traverse_bvh(bvh.nodes.data(), start, ray, counters, [&](NodeRef leaf) {
        const std::uint32_t end = leaf.first_prim() + leaf.prim_count();
        for (std::uint32_t i = leaf.first_prim(); i < end; ++i) {
            if (counters) ++counters->triangles_tested;
            float t, u, v;
            if (intersect_triangle(bvh.triangles[i], ray.org, ray.dir, ray.tnear, ray.tfar, t, u,
                                   v))
                return true;
        }
        return false;
    });
}

}  // namespace rebraid
