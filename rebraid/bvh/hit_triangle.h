#pragma once

#include <cstdint>

#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/core/triangle.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// The terms of the Möller test (TriangleTest::moller) for a hit, before the division by
/// |n.dir|, as the SIMD kernels computed them in the object space the ray was traced in:
/// u = scaled_u / abs_den, v = scaled_v / abs_den, t = scaled_t / abs_den, and the
/// unnormalised normal n = (v2 - v0) x (v0 - v1). A caller that must report Embree's
/// attributes to the last bit finishes them with Embree's reciprocal instead of computing
/// the test again (embree_glue).
struct MollerTerms {
    float scaled_u = 0.0f, scaled_v = 0.0f, scaled_t = 0.0f, abs_den = 0.0f;
    Vec3f normal;
};

/// Where the leaf data the query tested keeps a triangle's corners: the triangle itself
/// (ObjectBvh::triangles), or its first entry in its leaf's rows (leaf_row_corners).
struct CornerLocation {
    const TriangleVerts* triangle = nullptr;
    const float* rows = nullptr;
    std::uint32_t stride = 0;

    /// The corners kept there; zeros where nothing is named (a miss).
    TriangleVerts read() const {
        if (triangle != nullptr) return *triangle;
        return rows != nullptr ? leaf_row_corners(rows, stride) : TriangleVerts{};
    }
};

/// Where a hit triangle is kept in its object BVH, and where its corners can be read (object
/// space): what a caller that recomputes hit attributes from the triangle reads next.
struct HitTriangle {
    /// Leaf-order position: index into ObjectBvh::triangles and ObjectBvh::prim_ids;
    /// kInvalidId when the ray hits nothing.
    std::uint32_t leaf_position = kInvalidId;
    /// Where the corners are kept: the query notes where rather than copying them at each
    /// closer hit, as most callers finish the hit from its Möller terms and never read them.
    /// Points into the structure: valid while it lives and is not updated.
    CornerLocation corner_location;
    /// The Möller test's terms of the hit, when the query ran that test in a SIMD kernel
    /// (has_moller_terms); the portable kernels and the watertight test leave them out.
    MollerTerms moller_terms;
    bool has_moller_terms = false;

    /// The corners as the structure keeps them (zeros for a miss).
    TriangleVerts corners() const { return corner_location.read(); }
};

}  // namespace rebraid
