#include "rebraid/rebraiding/bref_bounds.h"

#include <algorithm>
#include <cmath>

#include "rebraid/bvh/vertex_world_bounds.h"

namespace rebraid {
namespace {

/// The box of `count` leaf triangles' transformed corners, widened by a few float ulps of its
/// magnitude: the box test in world space and the triangle test in object space round
/// differently, and a hit on the box's extreme vertex must not be culled.
BBox3f transformed_leaf_bounds(const ObjectBvh& bvh, NodeRef leaf,
                               const AffineTransform& to_world) {
    BBox3f box;
    const std::uint32_t first = leaf.first_prim();
    for (std::uint32_t i = first; i < first + leaf.prim_count(); ++i) {
        const TriangleVerts& t = bvh.triangles[i];
        box.extend(to_world.transform_point(t.v0));
        box.extend(to_world.transform_point(t.v1));
        box.extend(to_world.transform_point(t.v2));
    }
    float magnitude = 0.0f;
    for (int axis = 0; axis < 3; ++axis)
        magnitude = std::max({magnitude, std::fabs(box.min[axis]), std::fabs(box.max[axis])});
    const float pad = magnitude * 0x1p-20f;  // 8 ulps at the box's largest coordinate
    box.min = box.min - Vec3f{pad, pad, pad};
    box.max = box.max + Vec3f{pad, pad, pad};
    return box;
}

}  // namespace

BBox3f bref_world_bounds(const ObjectBvh& bvh, NodeRef node, const BBox3f& node_box,
                         const AffineTransform& to_world, BRefBoundsRule rule,
                         const ObjectSupportTables* tables) {
    // Under a map that takes boxes to boxes, the node's box (the tight box of its triangles)
    // maps to the box of its mapped vertices: every rule gives it, without a search.
    if (rule == BRefBoundsRule::transformed_box || node.is_empty() ||
        to_world.maps_boxes_to_boxes())
        return to_world.transform_bbox_conservative(node_box);
    // A triangle that spatial splits cut sits in several leaves, each box holding only its
    // part there: its vertices reach beyond the node, so the vertices' box is cut down to the
    // node's mapped box (both hold the node's parts of its triangles).
    const BBox3f mapped_box = to_world.transform_bbox_conservative(node_box);
    if (node.is_leaf())
        return intersection(transformed_leaf_bounds(bvh, node, to_world), mapped_box);
    if (rule == BRefBoundsRule::transformed_vertices) {
        if (const SupportTable* table = tables ? tables->find(node) : nullptr)
            return intersection(table->table_world_bounds(to_world), mapped_box);
        return intersection(vertex_world_bounds(bvh, node, node_box, to_world), mapped_box);
    }
    const WideNode& wide = bvh.nodes[node.node_id()];
    BBox3f box;
    for (int c = 0; c < kBvhWidth && !wide.children[c].is_empty(); ++c)
        box.extend(to_world.transform_bbox_conservative(wide.child_bounds(c)));
    return box;
}

}  // namespace rebraid
