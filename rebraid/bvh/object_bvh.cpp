#include "rebraid/bvh/object_bvh.h"

#include "rebraid/bvh/leaf_row_hints.h"
#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/object_subtree_counts.h"

namespace rebraid {
std::uint64_t ObjectBvh::memory_bytes() const {
    return nodes.size() * sizeof(WideNode) + prim_ids.size() * sizeof(PrimId) +
           triangles.size() * sizeof(TriangleVerts) + leaf_rows.size() * sizeof(float) +
           node_prim_counts.size() * sizeof(std::uint32_t);
}

void ObjectBvh::refresh_node_prim_counts() {
    if (!node_prim_counts.empty()) node_prim_counts = subtree_prim_counts(*this);
}

void ObjectBvh::refresh_leaf_rows() {
    if (leaf_rows.empty()) return;
    rewrite_leaf_rows(nodes, root, triangles, prim_ids, leaf_rows);
    refresh_leaf_row_hints();
}

void ObjectBvh::refresh_leaf_row_hints() {
    if (!leaf_rows.empty()) write_leaf_row_hints(nodes);
}

}  // namespace rebraid
