#pragma once

#include <cstdint>

#include "rebraid/core/ray.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// A closest hit and where its triangle is kept: its position in the leaf order of its mesh's
/// object BVH (index into ObjectBvh::triangles and ObjectBvh::prim_ids). For callers that read
/// the hit triangle's corners right after the query (the Embree glue recomputes Embree's hit
/// attributes from them): the query prefetches them with every closer hit it finds, so that
/// their cache miss overlaps the rest of the traversal.
struct LocatedHit {
    Hit hit;
    /// kInvalidId when the ray hits nothing.
    std::uint32_t leaf_position = kInvalidId;
};

}  // namespace rebraid
