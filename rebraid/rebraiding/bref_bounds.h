#pragma once

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/object_support_tables.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/transform.h"

namespace rebraid {

/// How a BRef's world-space box is computed for an instanced (transformed) object node.
enum class BRefBoundsRule {
    /// The node's object-space box transformed, i.e. the box of its 8 transformed corners
    /// (paper §5.4: "a conservative AABB based on the child's AABB transformed by the
    /// instance's transformation matrix").
    transformed_box,
    /// One level tighter: the union of the node's children's boxes, each transformed; for a
    /// leaf, the box of its triangles' transformed corners. Under rotation the transformed
    /// box of a union grows much faster than the union of transformed parts, so opened
    /// BRefs of rotated instances lose less of their object-space tightness. Costs one read
    /// of the node per BRef; for identity transforms both rules give the same box.
    transformed_children,
    /// Tight: the box of the node's transformed vertices to within 1 % of its extent
    /// (vertex_world_bounds.h), found by branch and bound over the object BVH in a few
    /// root-to-leaf paths per face. Under a transform that takes boxes to boxes
    /// (AffineTransform::maps_boxes_to_boxes) the transformed node box is that box already,
    /// and no search is made.
    transformed_vertices,
};

/// World-space bounds of the BRef to `node` of `bvh` placed by `to_world`; `node_box` is the
/// node's object-space box (as its parent stores it, or the BVH's bounds for the root).
/// Under transformed_vertices, a node with a table in `tables` takes its box from the table
/// alone (SupportTable::table_world_bounds: no search of the BVH, each face within the
/// grid's error of the vertices' box, a few percent of the extent at most, and never wider
/// than transformed_box's).
BBox3f bref_world_bounds(const ObjectBvh& bvh, NodeRef node, const BBox3f& node_box,
                         const AffineTransform& to_world, BRefBoundsRule rule,
                         const ObjectSupportTables* tables = nullptr);

}  // namespace rebraid
