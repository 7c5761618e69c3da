#include "rebraid/bvh/object_bvh.h"

namespace rebraid {
std::uint64_t ObjectBvh::memory_bytes() const {
    return nodes.size() * sizeof(WideNode) + prim_ids.size() * sizeof(PrimId) +
           triangles.size() * sizeof(TriangleVerts);
}

}  // namespace rebraid
