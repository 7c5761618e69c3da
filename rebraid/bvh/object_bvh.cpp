#include "rebraid/bvh/object_bvh.h"

namespace rebraid {
std::uint64_t ObjectBvh::memory_bytes() const {
    return nodes.size() * sizeof(WideNode) + prim_ids.size() * sizeof(PrimId) +
           triangles.size() * sizeof(TriangleVerts) + leaf_rows.size() * sizeof(float);
}

void ObjectBvh::refresh_leaf_rows() {
    if (!leaf_rows.empty()) rewrite_leaf_rows(nodes, root, triangles, leaf_rows);
}

}  // namespace rebraid
