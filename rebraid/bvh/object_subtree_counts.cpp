#include "rebraid/bvh/object_subtree_counts.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "rebraid/core/error.h"

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

/// The counts in one backward sweep over the node array, reading only the child references
/// (a sequential pass, where the walk jumps around): valid when every inner child has a
/// larger id than its parent, so its count is known when the parent needs it. Returns false,
/// with `counts` partly filled, when a node breaks that order. Nodes the root does not reach
/// (none, in a well-formed BVH) get counts too; nobody reads them.
bool count_in_reverse_order(const ObjectBvh& bvh, std::vector<std::uint32_t>& counts) {
    for (std::size_t n = bvh.nodes.size(); n-- > 0;) {
        const WideNode& node = bvh.nodes[n];
        std::uint32_t sum = 0;
        for (int c = 0; c < kBvhWidth; ++c) {
            const NodeRef child = node.children[c];
            if (child.is_empty()) break;
            if (child.is_leaf()) {
                sum += child.prim_count();
            } else {
                if (child.node_id() <= n) return false;
                sum += counts[child.node_id()];
            }
        }
        counts[n] = sum;
    }
    return true;
}

}  // namespace

std::vector<std::uint32_t> subtree_prim_counts(const ObjectBvh& bvh) {
    std::vector<std::uint32_t> counts(bvh.nodes.size(), 0);
    if (bvh.root.is_inner() && !count_in_reverse_order(bvh, counts)) {
        std::fill(counts.begin(), counts.end(), 0u);
        count_below(bvh, bvh.root, counts);
    }
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

std::uint32_t object_ref_prim_count(const ObjectBvh& bvh, NodeRef ref,
                                    std::span<const std::uint32_t> node_prims) {
    if (ref.is_empty()) return 0;
    if (ref.is_leaf()) return ref.prim_count();
    if (ref == bvh.root) return bvh.prim_count();
    if (ref.node_id() >= node_prims.size())
        throw Error("object_ref_prim_count: node " + std::to_string(ref.node_id()) +
                    " has no count (" + std::to_string(node_prims.size()) + " counted)");
    return node_prims[ref.node_id()];
}

LazySubtreeCounts::LazySubtreeCounts(std::span<const ObjectBvh> object_bvhs)
    : object_bvhs_(object_bvhs),
      counts_(object_bvhs.size()),
      computed_(std::make_unique<std::once_flag[]>(object_bvhs.size())) {}

std::span<const std::uint32_t> LazySubtreeCounts::counts_of(std::uint32_t mesh) const {
    const ObjectBvh& bvh = object_bvhs_[mesh];
    // Counted at its build (and kept in step by the updates that regroup nodes).
    if (!bvh.node_prim_counts.empty() && bvh.node_prim_counts.size() == bvh.nodes.size())
        return bvh.node_prim_counts;
    std::call_once(computed_[mesh],
                   [&] { counts_[mesh] = subtree_prim_counts(object_bvhs_[mesh]); });
    return counts_[mesh];
}

std::uint32_t LazySubtreeCounts::item_prim_count(std::uint32_t mesh, NodeRef node) const {
    const ObjectBvh& bvh = object_bvhs_[mesh];
    // The root and leaves need no node counts: a whole-mesh item never pays for counting.
    const bool needs_counts = node.is_inner() && node != bvh.root;
    return object_ref_prim_count(bvh, node,
                                 needs_counts ? counts_of(mesh) : std::span<const std::uint32_t>{});
}

}  // namespace rebraid
