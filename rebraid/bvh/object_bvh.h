#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/bvh/leaf_rows.h"
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
    /// The same corners pre-arranged per leaf for the SIMD tests (leaf_rows.h); empty until
    /// made, and then kept in step with `triangles` by whatever changes them.
    std::vector<float> leaf_rows;
    /// Triangles below each inner node (index = node id; object_subtree_counts.h): what a
    /// re-braiding build reads to weigh the BRefs it opens, counted once per BVH rather than
    /// once per top-level build. Empty until counted, and then kept in step with `nodes` by
    /// whatever regroups them.
    std::vector<std::uint32_t> node_prim_counts;
    double build_ms = 0.0;

    std::uint32_t prim_count() const { return std::uint32_t(prim_ids.size()); }
    /// Writes leaf_rows again from `triangles` and the current leaves, in place (when made):
    /// what an update that regroups leaves calls last.
    void refresh_leaf_rows();
    /// Writes the nodes' leaf-row hints again (leaf_row_hints.h; when leaf_rows are made):
    /// what an update that regroups nodes calls last. refresh_leaf_rows() calls it.
    void refresh_leaf_row_hints();
    /// Counts node_prim_counts again from the current nodes (when counted): what an update
    /// that regroups nodes calls last.
    void refresh_node_prim_counts();
    /// Bytes held by the arrays above.
    std::uint64_t memory_bytes() const;
};

/// The arrays of an ObjectBvh a traversal reads, as bare pointers: what a two-level structure
/// keeps per instance, so that entering one reads a single record (valid while the ObjectBvh
/// lives and its arrays keep their size).
struct ObjectBvhView {
    const WideNode* nodes = nullptr;
    const TriangleVerts* triangles = nullptr;  ///< leaf order
    const PrimId* prim_ids = nullptr;          ///< leaf order -> triangle index in the mesh
    const float* leaf_rows = nullptr;          ///< ObjectBvh::leaf_rows past its padding
    /// Whether closest-hit queries ask for leaf rows ahead (prefetches_leaf_rows): by this
    /// BVH's rows alone, unless the structure holding the view decides for all its BVHs.
    bool prefetches_rows = false;

    ObjectBvhView() = default;
    ObjectBvhView(const ObjectBvh& bvh)  // NOLINT: a view converts implicitly, as a span does
        : nodes(bvh.nodes.data()),
          triangles(bvh.triangles.data()),
          prim_ids(bvh.prim_ids.data()),
          leaf_rows(bvh.leaf_rows.empty() ? nullptr : bvh.leaf_rows.data() + kLeafRowPadding),
          prefetches_rows(prefetches_leaf_rows(bvh.leaf_rows.size())) {}
};

}  // namespace rebraid
