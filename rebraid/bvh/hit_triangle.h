#pragma once

#include <cstdint>

#include "rebraid/core/triangle.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// Where a hit triangle is kept in its object BVH, and its corners as kept there (object
/// space): what a caller that recomputes hit attributes from the triangle reads next.
struct HitTriangle {
    /// Leaf-order position: index into ObjectBvh::triangles and ObjectBvh::prim_ids;
    /// kInvalidId when the ray hits nothing.
    std::uint32_t leaf_position = kInvalidId;
    TriangleVerts corners{};
};

}  // namespace rebraid
