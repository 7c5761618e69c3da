#pragma once

#include <cstdint>

#include "rebraid/bvh/hit_triangle.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// A closest hit and its triangle: where it is kept in the leaf order of its mesh's object
/// BVH, and its corners. For callers that recompute hit attributes from the corners right
/// after the query (the Embree glue recomputes Embree's): the query copies them from the leaf
/// data it has just tested as it finds each closer hit, where reading ObjectBvh::triangles
/// afterwards would cost a cache miss.
struct LocatedHit {
    Hit hit;
    HitTriangle triangle;
};

/// Told of every closer hit a located query finds, as it finds it (the last call names the
/// closest hit): a caller that computes something from the hit triangle can start while the
/// traversal goes on, instead of after it.
struct CloserHitObserver {
    void (*on_closer_hit)(void* context, InstanceId instance,
                          const HitTriangle& triangle) = nullptr;
    void* context = nullptr;
};

}  // namespace rebraid
