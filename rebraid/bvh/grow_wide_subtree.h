#pragma once

#include <tbb/task_group.h>

#include <array>
#include <cstdint>
#include <vector>

#include "rebraid/bvh/wide_node.h"

namespace rebraid {

/// The top-down recursion every wide-BVH builder of the project shares: a node is grown by
/// splitting its child with the largest surface area until it has kBvhWidth children or no
/// child is worth splitting (each split being one binary SAH step), then the children that
/// are not leaves recurse. What a range of primitives is, how it splits and how a leaf is
/// referenced is the builder's `Policy`:
///   std::array<Candidate, 2> split(const Candidate&, bool median_only) const;
///   NodeRef make_leaf(const Candidate&) const;
/// and a Candidate has `bool is_leaf`, `float area() const`, `BBox3f bounds() const` and
/// `std::size_t size() const`.
///
/// Subtrees of at least `parallel_threshold` primitives are built as TBB tasks into their own
/// node arrays, appended in child order afterwards, so node numbering never depends on which
/// task finished first. Past kSahDepthLimit levels, `median_only` asks the policy for index
/// splits, which bounds the depth by kMaxBvhDepth.
template <class Policy, class Candidate>
NodeRef grow_wide_subtree(const Policy& policy, const Candidate& root, std::uint32_t depth,
                          std::size_t parallel_threshold, std::vector<WideNode>& out) {
    const bool median_only = depth + 1 >= std::uint32_t(kSahDepthLimit);
    std::array<Candidate, kBvhWidth> kids;
    int kid_count = 0;
    for (Candidate& half : policy.split(root, median_only)) kids[kid_count++] = std::move(half);
    while (kid_count < kBvhWidth) {
        int pick = -1;
        float largest = -1.0f;
        for (int i = 0; i < kid_count; ++i)
            if (!kids[i].is_leaf && kids[i].area() > largest) {
                largest = kids[i].area();
                pick = i;
            }
        if (pick < 0) break;
        std::array<Candidate, 2> halves = policy.split(kids[pick], median_only);
        // Keep the halves adjacent: siblings in space stay siblings in memory.
        for (int i = kid_count; i > pick + 1; --i) kids[i] = std::move(kids[i - 1]);
        kids[pick] = std::move(halves[0]);
        kids[pick + 1] = std::move(halves[1]);
        ++kid_count;
    }

    const auto node_id = std::uint32_t(out.size());
    out.push_back(WideNode::make_empty());
    std::array<std::vector<WideNode>, kBvhWidth> chunks;
    std::array<NodeRef, kBvhWidth> chunk_roots;
    tbb::task_group tasks;
    for (int i = 0; i < kid_count; ++i) {
        const Candidate& kid = kids[i];
        if (kid.is_leaf) {
            out[node_id].set_child(i, policy.make_leaf(kid), kid.bounds());
        } else if (kid.size() >= parallel_threshold) {
            tasks.run([&, i] {
                chunk_roots[i] =
                    grow_wide_subtree(policy, kids[i], depth + 1, parallel_threshold, chunks[i]);
            });
        } else {
            const NodeRef child =
                grow_wide_subtree(policy, kid, depth + 1, parallel_threshold, out);
            out[node_id].set_child(i, child, kid.bounds());
        }
    }
    tasks.wait();
    for (int i = 0; i < kid_count; ++i) {
        if (chunks[i].empty()) continue;
        const auto offset = std::uint32_t(out.size());
        for (WideNode& node : chunks[i])
            for (NodeRef& ref : node.children)
                if (ref.is_inner()) ref = NodeRef::inner(ref.node_id() + offset);
        out.insert(out.end(), chunks[i].begin(), chunks[i].end());
        out[node_id].set_child(i, NodeRef::inner(chunk_roots[i].node_id() + offset),
                               kids[i].bounds());
    }
    return NodeRef::inner(node_id);
}

}  // namespace rebraid
