#pragma once

#include <cstdint>

#include "rebraid/bvh/hit_triangle.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// A closest hit and its triangle: where it is kept in the leaf order of its mesh's object
/// BVH, its Möller terms, and where its corners are. For callers that finish or recompute hit
/// attributes right after the query (the Embree glue gives Embree's): the corners are read from
/// the leaf data the query has just tested (HitTriangle::corners), still in the caches, and
/// only by a caller that needs them.
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
