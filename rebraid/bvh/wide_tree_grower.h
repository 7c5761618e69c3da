#pragma once

#include <tbb/task_group.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <optional>
#include <type_traits>
#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/huge_pages.h"

namespace rebraid {

/// The nodes one task of grow_wide_tree built: node 0 is its subtree's root, child references
/// to nodes of the same chunk hold local ids, and subtrees other tasks built hang off it as
/// links (their references hold the index into `links`).
struct GrownChunk {
    std::vector<WideNode> nodes;
    /// Per node: bit s set when child slot s is an inner node of at least the layout
    /// threshold's size (numbered after its smaller siblings' subtrees).
    std::vector<std::uint8_t> late_slots;
    /// Per node: bit s set when child slot s refers into `links` rather than `nodes`.
    std::vector<std::uint8_t> linked_slots;
    std::vector<std::unique_ptr<GrownChunk>> links;
    /// Per node: the nodes of its subtree, itself and linked chunks included (what placing
    /// the subtrees side by side needs to number them without walking them first).
    std::vector<std::uint32_t> subtree_nodes;
    /// Whether any node has late slots (else, without links, `nodes` is in final order).
    bool has_late_slots = false;
};

namespace growth_detail {

/// Writes the subtree of `local` to out[id...] in grow_wide_subtree's numbering: the node,
/// then the subtrees of its smaller inner children in slot order, then those of its larger
/// ones (which grow_wide_subtree built as tasks and appended last). Each child's first id
/// follows from its siblings' subtree sizes, so large subtrees are placed in parallel into
/// their own ranges (subtrees of at least `task_nodes` nodes by tasks of their own); the
/// result does not depend on the task split.
inline void place(const GrownChunk& chunk, std::uint32_t local, std::uint32_t id, WideNode* out,
                  std::uint32_t task_nodes) {
    WideNode node = chunk.nodes[local];
    const std::uint32_t late = chunk.late_slots[local], linked = chunk.linked_slots[local];
    std::uint32_t next = id + 1;
    std::optional<tbb::task_group> tasks;
    for (std::uint32_t pass = 0; pass < 2; ++pass)
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef ref = node.children[slot];
            if (!ref.is_inner() || ((late >> slot) & 1u) != pass) continue;
            const bool is_linked = (linked >> slot) & 1u;
            const GrownChunk& owner = is_linked ? *chunk.links[ref.node_id()] : chunk;
            const std::uint32_t child_local = is_linked ? 0 : ref.node_id();
            const std::uint32_t child_id = next;
            next += owner.subtree_nodes[child_local];
            node.children[slot] = NodeRef::inner(child_id);
            if (owner.subtree_nodes[child_local] >= task_nodes) {
                if (!tasks) tasks.emplace();
                tasks->run([&owner, child_local, child_id, out, task_nodes] {
                    place(owner, child_local, child_id, out, task_nodes);
                });
            } else {
                place(owner, child_local, child_id, out, task_nodes);
            }
        }
    out[id] = node;
    if (tasks) tasks->wait();
}

}  // namespace growth_detail

/// The tree and node numbering of grow_wide_subtree (grow_wide_subtree.h) with
/// `layout_threshold` as its parallel threshold, whatever the task granularity: subtrees of
/// at least `task_threshold` primitives are built as TBB tasks into chunks of their own, and
/// one pass at the end numbers every node as grow_wide_subtree would have. So tasks can be
/// as fine as the load needs without changing a single bit of the result, on any thread
/// count. Same Policy and Candidate requirements as grow_wide_subtree, and Candidate must be
/// trivially copyable; `root` must not be a leaf. Fills `out` (cleared first) and returns the
/// root's reference.
template <class Policy, class Candidate>
class WideTreeGrower {
    static_assert(std::is_trivially_copyable_v<Candidate> &&
                  std::is_trivially_destructible_v<Candidate>);

public:
    /// Subtrees of at least this many nodes are numbered into place by tasks of their own.
    static constexpr std::uint32_t kPlaceTaskNodes = 4096;

    WideTreeGrower(const Policy& policy, std::size_t layout_threshold, std::size_t task_threshold,
                   std::uint32_t place_task_nodes = kPlaceTaskNodes)
        : policy_(policy),
          layout_threshold_(layout_threshold),
          task_threshold_(task_threshold),
          place_task_nodes_(place_task_nodes) {}

    NodeRef grow(const Candidate& root, std::vector<WideNode>& out) const {
        GrownChunk chunk;
        reserve_on_huge_pages(chunk.nodes, expected_nodes(root.size()));
        grow_into(root, 0, chunk);
        out.clear();
        if (chunk.links.empty() && !chunk.has_late_slots) {
            out = std::move(chunk.nodes);  // built in its final order already
            return NodeRef::inner(0);
        }
        const std::uint32_t total = chunk.subtree_nodes[0];
        reserve_on_huge_pages(out, total);
        out.resize(total);
        growth_detail::place(chunk, 0, 0, out.data(), place_task_nodes_);
        return NodeRef::inner(0);
    }

private:
    /// Room for the nodes a subtree of `prim_count` primitives likely needs (leaves of one
    /// or a few, up to kBvhWidth children per node): growing node arrays copy and touch
    /// fresh pages again.
    static std::size_t expected_nodes(std::size_t prim_count) { return 1 + prim_count / 4; }

    /// Builds the subtree of `c` into `chunk`; returns its root's local id.
    std::uint32_t grow_into(const Candidate& c, std::uint32_t depth, GrownChunk& chunk) const {
        const bool median_only = depth + 1 >= std::uint32_t(kSahDepthLimit);
        // Kids stay where they were made; `order` lists them by slot, so inserting a split's
        // second half moves one byte per later slot rather than whole candidates. Their room
        // is left uninitialised: a default-constructed array would be written in full at
        // every node.
        alignas(Candidate) std::byte kid_bytes[sizeof(Candidate) * kBvhWidth];
        Candidate* const kids = reinterpret_cast<Candidate*>(kid_bytes);
        std::array<std::uint8_t, kBvhWidth> order{0, 1};
        {
            std::array<Candidate, 2> halves = policy_.split(c, median_only);
            new (kids) Candidate(std::move(halves[0]));
            new (kids + 1) Candidate(std::move(halves[1]));
        }
        int kid_count = 2;
        while (kid_count < kBvhWidth) {
            int pick = -1;
            float largest = -1.0f;
            for (int i = 0; i < kid_count; ++i) {
                const Candidate& kid = kids[order[i]];
                if (!kid.is_leaf && kid.area() > largest) {
                    largest = kid.area();
                    pick = i;
                }
            }
            if (pick < 0) break;
            std::array<Candidate, 2> halves = policy_.split(kids[order[pick]], median_only);
            kids[order[pick]] = std::move(halves[0]);
            new (kids + kid_count) Candidate(std::move(halves[1]));
            // Keep the halves adjacent: siblings in space stay siblings in memory.
            for (int i = kid_count; i > pick + 1; --i) order[i] = order[i - 1];
            order[pick + 1] = std::uint8_t(kid_count);
            ++kid_count;
        }

        const auto node_id = std::uint32_t(chunk.nodes.size());
        chunk.nodes.push_back(WideNode::make_empty());
        chunk.subtree_nodes.push_back(0);  // counted once the children are built
        std::uint8_t late = 0, linked = 0;
        std::array<GrownChunk*, kBvhWidth> own_chunk{};
        std::array<std::uint32_t, kBvhWidth> link_index{};
        int last_task = -1;
        for (int i = 0; i < kid_count; ++i) {
            const Candidate& kid = kids[order[i]];
            if (kid.is_leaf) continue;
            if (kid.size() >= layout_threshold_) late |= std::uint8_t(1u << i);
            if (kid.size() < task_threshold_) continue;
            link_index[i] = std::uint32_t(chunk.links.size());
            chunk.links.push_back(std::make_unique<GrownChunk>());
            own_chunk[i] = chunk.links.back().get();
            reserve_on_huge_pages(own_chunk[i]->nodes, expected_nodes(kid.size()));
            linked |= std::uint8_t(1u << i);
            last_task = i;
        }
        chunk.late_slots.push_back(late);
        chunk.has_late_slots |= late != 0;
        chunk.linked_slots.push_back(linked);
        // Most nodes spawn nothing: a task_group (a context registration) only when needed.
        // The last large child runs on this thread, saving a spawn.
        std::optional<tbb::task_group> tasks;
        for (int i = 0; i < last_task; ++i) {
            if (!own_chunk[i]) continue;
            if (!tasks) tasks.emplace();
            tasks->run([this, &kid = kids[order[i]], depth, sub = own_chunk[i]] {
                grow_into(kid, depth + 1, *sub);
            });
        }
        for (int i = 0; i < kid_count; ++i) {
            const Candidate& kid = kids[order[i]];
            NodeRef child;
            if (kid.is_leaf)
                child = policy_.make_leaf(kid);
            else if (own_chunk[i])
                child = NodeRef::inner(link_index[i]);
            else
                child = NodeRef::inner(grow_into(kid, depth + 1, chunk));
            // After the recursion: it may have grown (and moved) chunk.nodes.
            chunk.nodes[node_id].set_child(i, child, kid.bounds());
        }
        if (last_task >= 0) grow_into(kids[order[last_task]], depth + 1, *own_chunk[last_task]);
        if (tasks) tasks->wait();
        std::uint32_t subtree = 1;
        for (int i = 0; i < kid_count; ++i) {
            const NodeRef child = chunk.nodes[node_id].children[i];
            if (!child.is_inner()) continue;
            subtree += own_chunk[i] ? own_chunk[i]->subtree_nodes[0]
                                    : chunk.subtree_nodes[child.node_id()];
        }
        chunk.subtree_nodes[node_id] = subtree;
        return node_id;
    }

    const Policy& policy_;
    std::size_t layout_threshold_;
    std::size_t task_threshold_;
    std::uint32_t place_task_nodes_;
};

}  // namespace rebraid
