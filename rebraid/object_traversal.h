#pragma once

#include <algorithm>

#include "rebraid/object_bvh.h"
#include "rebraid/traversal.h"
#include "rebraid/triangle_group.h"

namespace rebraid {

/// Closest hit among the triangles below `start` (any node of `bvh`), for a ray already in
/// the BVH's space. On a closer hit sets ray.tfar and hit.t/u/v, and hit.prim_id to the hit's
/// position in leaf order (index into bvh.prim_ids and bvh.triangles), and returns true;
/// leaves hit.instance_id to the caller.
inline bool intersect_object_bvh_leaf_order(const ObjectBvh& bvh, NodeRef start,
                                            TraversalRay& ray, Hit& hit,
                                            TraversalCounters* counters) {
    const TriangleGroupRay group_ray(ray.org, ray.dir);
    const TriangleVerts* triangles = bvh.triangles.data();
    bool found = false;
    traverse_bvh(bvh.nodes.data(), start, ray, counters, [&](NodeRef leaf) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        for (std::uint32_t done = 0; done < count; done += kTriangleGroupSize) {
            TriangleGroupHit group_hit;
            if (intersect_triangle_group(triangles + first + done,
                                         std::min(count - done, kTriangleGroupSize), group_ray,
                                         ray.tnear, ray.tfar, group_hit)) {
                ray.tfar = group_hit.t;
                hit.t = group_hit.t;
                hit.u = group_hit.u;
                hit.v = group_hit.v;
                hit.prim_id = first + done + group_hit.index;
                found = true;
            }
        }
        if (counters) counters->triangles_tested += count;
        return false;
    });
    return found;
}

/// Closest hit among the triangles below `start` (any node of `bvh`), for a ray already in
/// the BVH's space. On a closer hit sets ray.tfar and hit.t/u/v/prim_id (mesh primID) and
/// returns true; leaves hit.instance_id to the caller.
inline bool intersect_object_bvh(const ObjectBvh& bvh, NodeRef start, TraversalRay& ray, Hit& hit,
                                 TraversalCounters* counters) {
    Hit leaf_order_hit = hit;
    if (!intersect_object_bvh_leaf_order(bvh, start, ray, leaf_order_hit, counters)) return false;
    hit = leaf_order_hit;
    hit.prim_id = bvh.prim_ids[leaf_order_hit.prim_id];
    return true;
}

/// True when any triangle below `start` is hit within [ray.tnear, ray.tfar].
inline bool occluded_object_bvh(const ObjectBvh& bvh, NodeRef start, TraversalRay& ray,
                                TraversalCounters* counters) {
    const TriangleGroupRay group_ray(ray.org, ray.dir);
    const TriangleVerts* triangles = bvh.triangles.data();
    return traverse_bvh<TraversalOrder::any>(
        bvh.nodes.data(), start, ray, counters, [&](NodeRef leaf) {
            const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
            if (counters) counters->triangles_tested += count;
            for (std::uint32_t done = 0; done < count; done += kTriangleGroupSize)
                if (occluded_triangle_group(triangles + first + done,
                                            std::min(count - done, kTriangleGroupSize),
                                            group_ray, ray.tnear, ray.tfar))
                    return true;
            return false;
        });
}

}  // namespace rebraid
