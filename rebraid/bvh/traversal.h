#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "rebraid/bvh/node_box_test.h"
#include "rebraid/bvh/prepared_ray.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/simd_config.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// How traverse_bvh orders the children a ray enters.
enum class TraversalOrder {
    /// Nearest child first, farther ones stacked with their entry distance and skipped when a
    /// hit closer than that distance was found meanwhile: closest-hit queries.
    nearest_first,
    /// Children in slot order, no sorting: any-hit queries, where the first hit ends the
    /// traversal and ordering costs more than it saves.
    any,
};

/// How traverse_bvh hands leaves to its visitor.
enum class LeafVisits {
    /// A leaf is a child like an inner node: stacked and visited nearest first, one at a
    /// time, as visit_leaf(NodeRef leaf). For costly leaves (top-level items, each entering
    /// an object BVH), where visiting the nearest first saves whole object traversals.
    one_by_one,
    /// At an inner node, the leaf children the ray enters are handed over together, before
    /// the node's inner children, as visit_leaf(const NodeRef* refs, unsigned slots) (bit i
    /// of slots selects refs[i]); a leaf start arrives as visit_leaf(&start, 1). For leaves
    /// of a few triangles: the visitor tests them in one go, without a stack entry each, and
    /// the hits found shorten the ray before any inner sibling is entered.
    with_siblings,
    /// Per slot, as the visitor says: at an inner node, the leaf children in
    /// visit_leaf.sibling_leaf_slots(node) that the ray enters are handed over together
    /// (visit_leaf(node, slots), node the WideNode), as with_siblings does, and the other
    /// leaves are stacked and visited one by one (visit_leaf(NodeRef leaf)). For a tree that
    /// holds both kinds of leaves (a top level with object nodes and leaves merged in:
    /// merged_top_level.h). The start must be an inner node.
    by_node,
};

/// Asks the cache for the node `ref` names (all four of its cache lines).
inline void prefetch_node(const WideNode* nodes, NodeRef ref) {
    const char* base = reinterpret_cast<const char*>(nodes + ref.node_id());
    for (int offset = 0; offset < int(sizeof(WideNode)); offset += 64)
        __builtin_prefetch(base + offset);
}

/// A leaf prefetcher that does nothing (traverse_bvh's default).
struct NoLeafPrefetch {
    void operator()(NodeRef) const {}
};

/// Depth-first traversal of the wide BVH `nodes` from `start` (any node, or a leaf
/// reference) for a ray prepared in the BVH's space. `visit_leaf` tests leaves' primitives
/// (one leaf or several, see LeafVisits), shrinking prepared.ray.tfar on hits, and returns true to
/// stop traversal (any-hit queries). Returns whether traversal was stopped by visit_leaf.
/// `prefetch_leaf(NodeRef leaf)` is called for hit leaves that wait on the stack (leaves
/// visited one by one), and every stacked inner node is prefetched: on scenes larger
/// than the caches, the misses of the siblings then overlap with the work on the nearest
/// child instead of following it. A prefetcher with `rows_of_child(node, node_id, slot)` is
/// also told each inner child the traversal descends into without the stack
/// (LeafRowsPrefetch, leaf_row_hints.h).
template <TraversalOrder order = TraversalOrder::nearest_first,
          LeafVisits leaf_visits = LeafVisits::one_by_one, class LeafVisitor,
          class LeafPrefetcher = NoLeafPrefetch>
bool traverse_bvh(const WideNode* nodes, NodeRef start, PreparedRay& prepared,
                  TraversalCounters* counters, LeafVisitor&& visit_leaf,
                  LeafPrefetcher&& prefetch_leaf = {}) {
    constexpr bool kWithSiblings = leaf_visits == LeafVisits::with_siblings;
    constexpr bool kByNode = leaf_visits == LeafVisits::by_node;
    constexpr bool kPrefetchesRows = requires {
        prefetch_leaf.rows_of_child(std::declval<const WideNode&>(), 0u, 0);
    };
    if constexpr (kWithSiblings) {
        if (start.is_leaf()) return visit_leaf(&start, 1u);
    }
    // A stack entry packs a child's entry distance (high half, as float bits) with its
    // reference (low half); for the non-negative distances of valid rays, comparing entries
    // as integers compares distances. The array is left uninitialised on purpose: clearing
    // its ~3.8 KB per ray once cost more than the whole traversal.
    constexpr int kStackCapacity = kMaxBvhDepth * (kBvhWidth - 1) + 1;
    std::uint64_t stack[kStackCapacity];
    int stack_size = 0;
    const auto entry_ref = [](std::uint64_t entry) {
        return std::bit_cast<NodeRef>(std::uint32_t(entry));
    };
    const auto entry_distance = [](std::uint64_t entry) {
        return std::bit_cast<float>(std::uint32_t(entry >> 32));
    };
    const auto make_entry = [&](NodeRef ref, float distance) {
        if (ref.is_leaf())
            prefetch_leaf(ref);
        else
            prefetch_node(nodes, ref);
        return (std::uint64_t(std::bit_cast<std::uint32_t>(distance)) << 32) | ref.bits();
    };
    TraversalRay& ray = prepared.ray;
    // A copy of the ray's box-test values that nothing outside this loop can reach: the
    // compiler then keeps them in registers across the visitor's code. Read through
    // `prepared`, whose address the query hands to the code entering items, they were
    // loaded from memory at every node of a re-braided query (kernel_ab.py, rebraid:
    // two_cylinder_engine 1.05, cg57_cruiser 1.03, brainstem 1.015; docs/design.md).
    const NodeBoxTest box_test = prepared.box_test;
    NodeRef current = start;
    for (;;) {
        while (current.is_inner()) {
            const std::uint32_t node_id = current.node_id();
            const WideNode& node = nodes[node_id];
            // The child references sit on the node's last cache line, which is read only once
            // the box test is done; asking for it now overlaps its miss with the test's.
            __builtin_prefetch(node.children);
            if (counters) ++counters->nodes_visited;
            alignas(32) float distances[kBvhWidth];
            unsigned mask = box_test(node, ray.tfar, distances);
            if constexpr (kWithSiblings || kByNode) {
                unsigned leaf_mask;
                if constexpr (kByNode)
                    leaf_mask = mask & visit_leaf.sibling_leaf_slots(node);
                else
                    leaf_mask = mask & leaf_slots(node);
                if (leaf_mask != 0) {
                    bool stop;
                    if constexpr (kByNode)
                        stop = visit_leaf(node, leaf_mask);
                    else
                        stop = visit_leaf(node.children, leaf_mask);
                    if (stop) return true;
                    // Their hits shortened the ray: keep the inner children still entered
                    // before its end (the test a stacked child gets when popped).
                    mask &= ~leaf_mask & entered_before(distances, ray.tfar);
                }
            }
            if (mask == 0) {
                current = NodeRef::empty();
                break;
            }
            const int first = std::countr_zero(mask);
            mask &= mask - 1;
            if (mask == 0) {  // one child hit: descend without touching the stack
                current = node.children[first];
                if constexpr (kPrefetchesRows) prefetch_leaf.rows_of_child(node, node_id, first);
                continue;
            }
            if constexpr (order == TraversalOrder::any) {
                current = node.children[first];
                do {
                    const int slot = std::countr_zero(mask);
                    mask &= mask - 1;
                    stack[stack_size++] = make_entry(node.children[slot], distances[slot]);
                } while (mask);
                continue;
            }
            const int second = std::countr_zero(mask);
            mask &= mask - 1;
            if (mask == 0) {  // two hits, the most common case: stack the farther one
                const bool first_is_near = distances[first] <= distances[second];
                const int near_slot = first_is_near ? first : second;
                const int far_slot = first_is_near ? second : first;
                stack[stack_size++] = make_entry(node.children[far_slot], distances[far_slot]);
                current = node.children[near_slot];
                if constexpr (kPrefetchesRows)
                    prefetch_leaf.rows_of_child(node, node_id, near_slot);
                continue;
            }
            // Three or more: push them all, sort the pushed run far to near (insertion sort,
            // runs are short), then continue with the nearest, popped again.
            const int run_begin = stack_size;
            stack[stack_size++] = make_entry(node.children[first], distances[first]);
            mask |= 1u << second;
            do {
                const int slot = std::countr_zero(mask);
                mask &= mask - 1;
                const std::uint64_t entry_key = make_entry(node.children[slot], distances[slot]);
                int j = stack_size++;
                while (j > run_begin && stack[j - 1] < entry_key) {
                    stack[j] = stack[j - 1];
                    --j;
                }
                stack[j] = entry_key;
            } while (mask);
            current = entry_ref(stack[--stack_size]);
        }
        if constexpr (!kWithSiblings) {
            if (current.is_leaf() && visit_leaf(current)) return true;
        }
        // Pop the nearest stacked subtree that may still hold a closer hit.
        for (;;) {
            if (stack_size == 0) return false;
            const std::uint64_t entry = stack[--stack_size];
            if (entry_distance(entry) <= ray.tfar) {
                current = entry_ref(entry);
                break;
            }
        }
    }
}

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
