#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/build_settings.h"
#include "rebraid/scene.h"
#include "rebraid/triangle.h"
#include "rebraid/wide_bvh_builder.h"
#include "rebraid/wide_node.h"

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

/// Builds an ObjectBvh with the project's parallel binned-SAH builder.
ObjectBvh build_object_bvh(const Mesh& mesh, const BuildSettings& settings = {});

/// Completes an ObjectBvh from a tree whose leaves index `leaf_prims` (primIDs of `mesh` in
/// leaf order), e.g. one made by Embree's rtcBuildBVH: copies the triangles in leaf order.
ObjectBvh make_object_bvh(const Mesh& mesh, WideBvh tree, std::vector<PrimId> leaf_prims);

/// One BuildPrim per triangle of `mesh` (bounds in object space, id = primID).
std::vector<BuildPrim> make_triangle_build_prims(const Mesh& mesh);

}  // namespace rebraid
