#include "rebraid/object_subtree_counts.h"

#include <tbb/parallel_for.h>

namespace rebraid {
namespace {

/// Triangles below `ref`, filling `counts` for the inner nodes on the way (post-order).
/// Recursion depth is bounded by kMaxBvhDepth.
std::uint32_t count_below(const ObjectBvh& bvh, NodeRef ref, std::vector<std::uint32_t>& counts) {
    if (ref.is_empty()) return 0;
    if (ref.is_leaf()) return ref.prim_count();
    const WideNode& node = bvh.nodes[ref.node_id()];
    std::uint32_t sum = 0;
    for (int c = 0; c < kBvhWidth && !node.children[c].is_empty(); ++c)
        sum += count_below(bvh, node.children[c], counts);
    counts[ref.node_id()] = sum;
    return sum;
}

}  // namespace

std::vector<std::uint32_t> subtree_prim_counts(const ObjectBvh& bvh) {
    std::vector<std::uint32_t> counts(bvh.nodes.size(), 0);
    count_below(bvh, bvh.root, counts);
    return counts;
}

std::vector<std::vector<std::uint32_t>> subtree_prim_counts(const Scene& scene,
                                                            std::span<const ObjectBvh> object_bvhs,
                                                            std::span<const InstanceId> instances) {
    std::vector<char> used(object_bvhs.size(), 0);
    for (const InstanceId i : instances) used[scene.instances[i].mesh_id] = 1;
    std::vector<std::vector<std::uint32_t>> counts(object_bvhs.size());
    tbb::parallel_for(std::size_t(0), object_bvhs.size(), [&](std::size_t m) {
        if (used[m]) counts[m] = subtree_prim_counts(object_bvhs[m]);
    });
    return counts;
}

}  // namespace rebraid
