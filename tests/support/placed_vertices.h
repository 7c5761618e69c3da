#pragma once

#include <algorithm>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/transform.h"

namespace rebraid::test {

/// The box of every vertex of the triangles under `ref` of `bvh` as transform_point maps it,
/// by a plain pass: what tight world bounds of an instanced node must hold.
inline BBox3f placed_vertex_bounds(const ObjectBvh& bvh, NodeRef ref,
                                   const AffineTransform& to_world) {
    BBox3f box;
    if (ref.is_leaf()) {
        for (std::uint32_t i = ref.first_prim(); i < ref.first_prim() + ref.prim_count(); ++i)
            for (Vec3f v : {bvh.triangles[i].v0, bvh.triangles[i].v1, bvh.triangles[i].v2})
                box.extend(to_world.transform_point(v));
        return box;
    }
    const WideNode& node = bvh.nodes[ref.node_id()];
    for (int c = 0; c < kBvhWidth && !node.children[c].is_empty(); ++c)
        box.extend(placed_vertex_bounds(bvh, node.children[c], to_world));
    return box;
}

/// How far `outer` reaches past `inner` at its farthest face.
inline float largest_gap(const BBox3f& outer, const BBox3f& inner) {
    float gap = 0.0f;
    for (int axis = 0; axis < 3; ++axis)
        gap = std::max({gap, inner.min[axis] - outer.min[axis], outer.max[axis] - inner.max[axis]});
    return gap;
}

}  // namespace rebraid::test
