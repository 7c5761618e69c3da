#pragma once

#include <algorithm>
#include <cstdint>

#include "rebraid/object_bvh.h"
#include "rebraid/simd_config.h"
#include "rebraid/traversal.h"
#include "rebraid/triangle_group.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// Asks the cache for the first and last line of `count` consecutive elements at `first`.
template <class T>
void prefetch_range(const T* first, std::uint32_t count) {
    __builtin_prefetch(first);
    __builtin_prefetch(reinterpret_cast<const char*>(first + count) - 1);
}

/// A leaf-data prefetcher that does nothing (intersect_object_bvh_leaf_order's default).
struct NoLeafDataPrefetch {
    void operator()(std::uint32_t, std::uint32_t) const {}
};

/// Closest hit among the triangles below `start` (any node of `bvh`), for a ray already in
/// the BVH's space. On a closer hit sets ray.tfar and hit.t/u/v, and hit.prim_id to the hit's
/// position in leaf order (index into bvh.prim_ids and bvh.triangles), and returns true;
/// leaves hit.instance_id to the caller.
/// `prefetch_leaf_data(first, count)` is called for every leaf as it is stacked or visited,
/// with its range in leaf order: the caller prefetches what it will look up for a hit there
/// (ids in leaf order), so that lookup does not add a cache miss after traversal.
template <class LeafDataPrefetch = NoLeafDataPrefetch>
bool intersect_object_bvh_leaf_order(const ObjectBvh& bvh, NodeRef start, TraversalRay& ray,
                                     Hit& hit, TraversalCounters* counters,
                                     LeafDataPrefetch&& prefetch_leaf_data = {}) {
    const TriangleGroupRay group_ray(ray.org, ray.dir);
    const TriangleVerts* triangles = bvh.triangles.data();
    bool found = false;
    const auto visit_leaf = [&](NodeRef leaf) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        prefetch_leaf_data(first, count);
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
    };
    const auto prefetch_leaf = [&](NodeRef leaf) {
        prefetch_range(triangles + leaf.first_prim(), leaf.prim_count());
        prefetch_leaf_data(leaf.first_prim(), leaf.prim_count());
    };
    traverse_bvh(bvh.nodes.data(), start, ray, counters, visit_leaf, prefetch_leaf);
    return found;
}

/// Closest hit among the triangles below `start` (any node of `bvh`), for a ray already in
/// the BVH's space. On a closer hit sets ray.tfar and hit.t/u/v/prim_id (mesh primID) and
/// returns true; leaves hit.instance_id to the caller.
inline bool intersect_object_bvh(const ObjectBvh& bvh, NodeRef start, TraversalRay& ray, Hit& hit,
                                 TraversalCounters* counters) {
    Hit leaf_order_hit = hit;
    const PrimId* prim_ids = bvh.prim_ids.data();
    const auto prefetch_prim_ids = [prim_ids](std::uint32_t first, std::uint32_t) {
        // A leaf's primIDs (4 bytes a triangle) nearly always share the line of its first one.
        __builtin_prefetch(prim_ids + first);
    };
    if (!intersect_object_bvh_leaf_order(bvh, start, ray, leaf_order_hit, counters,
                                         prefetch_prim_ids))
        return false;
    hit = leaf_order_hit;
    hit.prim_id = prim_ids[leaf_order_hit.prim_id];
    return true;
}

/// True when any triangle below `start` is hit within [ray.tnear, ray.tfar].
inline bool occluded_object_bvh(const ObjectBvh& bvh, NodeRef start, TraversalRay& ray,
                                TraversalCounters* counters) {
    const TriangleGroupRay group_ray(ray.org, ray.dir);
    const TriangleVerts* triangles = bvh.triangles.data();
    const auto visit_leaf = [&](NodeRef leaf) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        if (counters) counters->triangles_tested += count;
        for (std::uint32_t done = 0; done < count; done += kTriangleGroupSize)
            if (occluded_triangle_group(triangles + first + done,
                                        std::min(count - done, kTriangleGroupSize), group_ray,
                                        ray.tnear, ray.tfar))
                return true;
        return false;
    };
    const auto prefetch_leaf = [triangles](NodeRef leaf) {
        prefetch_range(triangles + leaf.first_prim(), leaf.prim_count());
    };
    // Any order: the first hit ends the query, and sorting the children costs more than the
    // nearer hits it would find first (measured on the shared scenes).
    return traverse_bvh<TraversalOrder::any>(bvh.nodes.data(), start, ray, counters, visit_leaf,
                                             prefetch_leaf);
}

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
