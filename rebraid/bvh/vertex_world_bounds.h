#pragma once

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/transform.h"

namespace rebraid {

/// The world-space box of the triangles under `node` of `bvh` mapped by `to_world`, to within
/// `tolerance` of the node's projected extent per face (the transformed vertices instead
/// of the transformed box of paper §5.4: tighter instance bounds). Conservative: it holds
/// every transformed vertex, widened by a few float ulps of the coordinates involved so that the
/// world-space box test never culls a hit the object-space triangle test finds.
///
/// Each of the six faces is a support value (the largest projection of a vertex onto a row of
/// the transform, or its negation) found by branch and bound over the object BVH: children are
/// visited in the order of their boxes' bound on it, and skipped once their bound cannot beat
/// the best vertex found by more than the tolerance (their bound then counts instead), so a
/// face costs a few root-to-leaf paths rather than a pass over the subtree's triangles. A
/// tolerance of 0 gives the exact box of the vertices. `node_box` is the node's object-space
/// box (as its parent stores it, or the BVH's bounds for the root).
BBox3f vertex_world_bounds(const ObjectBvh& bvh, NodeRef node, const BBox3f& node_box,
                           const AffineTransform& to_world, float tolerance = 0.01f);

/// `box`, which holds points of an object (coordinates at most `object_magnitude` in absolute
/// value) mapped by `to_world` in a rounded computation, widened by `ulps` float ulps of the
/// largest term such a mapping sums: the terms' magnitude, not the result's, bounds the
/// rounding (a large object coordinate may be cancelled by the translation).
BBox3f widen_for_mapping_rounding(BBox3f box, const AffineTransform& to_world,
                                  float object_magnitude, float ulps);

/// One support value of that search: `value` is the largest `direction` · v over the vertices
/// of the triangles under `node`, or a bound at most `slack` above it (never below it, up to
/// the rounding of the projections); -infinity for an empty node. `vertex` is the vertex of
/// largest projection the search met. `start`, when given, must be one of those vertices:
/// starting from a good one (the answer for a nearby direction) prunes most of the search.
struct VertexSupport {
    float value;
    Vec3f vertex;
};
VertexSupport vertex_support(const ObjectBvh& bvh, NodeRef node, Vec3f direction, float slack,
                             const Vec3f* start = nullptr);

}  // namespace rebraid
