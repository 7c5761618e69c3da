#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/triangle.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// The BVH of one mesh, in object space. Leaf references index `prim_ids` and `triangles`,
/// which are in leaf order. Any node of it can be the start of a traversal (top levels and
/// re-braiding reference inner nodes and leaves directly).
struct ObjectBvh {
    std::vector<WideNode> nodes;
    NodeRef root = NodeRef::empty();
    BBox3f bounds;
    std::vector<PrimId> prim_ids;          ///< leaf order -> triangle index in the mesh
    std::vector<TriangleVerts> triangles;  ///< leaf order -> corners, copied from the mesh
    double build_ms = 0.0;

    std::uint32_t prim_count() const { return std::uint32_t(prim_ids.size()); }
    /// Bytes held by the arrays above.
    std::uint64_t memory_bytes() const;
};

}  // namespace rebraid
