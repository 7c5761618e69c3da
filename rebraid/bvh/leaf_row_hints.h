#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/wide_node.h"

namespace rebraid {

/// A leaf-row hint: where the rows of an inner node's first leaf children start (leaf-order
/// position, low bits) and how many cache lines they span (high bits; 0: no hint).
inline constexpr int kLeafRowHintLineShift = 27;
/// At most this many lines are asked for: a node's leaf children hold up to 8 x 8 triangles,
/// 40 bytes each, and asking for all of them cost more than it gained on scenes that fit the
/// caches (two_cylinder_engine's flat BVH 0.96 of the speed without hints at 31 lines, 0.99
/// at 6, 1.01 at 4; the default scene's 1.05, 1.08 and 1.05; docs/design.md).
inline constexpr std::uint32_t kMaxLeafRowHintLines = 6;
/// The bits of the line count: the two above them stay free (a merged top level's copied
/// nodes flag the words that name their source with the top one, MergedTopLevel).
inline constexpr std::uint32_t kLeafRowHintLineMask = 7;
static_assert(kMaxLeafRowHintLines <= kLeafRowHintLineMask);

/// The cache lines hint `hint` asks for (0: none).
constexpr std::uint32_t leaf_row_hint_lines(std::uint32_t hint) {
    return (hint >> kLeafRowHintLineShift) & kLeafRowHintLineMask;
}

/// The hint for entering `node`: its first leaf child's rows and those of the leaf children
/// after it whose triangles follow in leaf order (0 without leaf children).
std::uint32_t leaf_row_hint(const WideNode& node);

/// Writes each inner node's leaf-row hints (WideNode::leaf_row_hints): for slot s with an inner
/// child C, the rows of C's first leaf child (slot order) and of the leaf children after it
/// whose triangles follow in leaf order; 0 where the child is a leaf, empty, or has no leaf
/// children. The traversal asks for those rows as it enters C, so that their cache misses
/// overlap the ones of C's own node instead of following its box test.
void write_leaf_row_hints(std::vector<WideNode>& nodes);

/// traverse_bvh's leaf prefetcher for object BVHs with leaf rows: as a closest-hit traversal
/// descends into an inner child, it asks for the rows of that child's leaf children (WideNode::
/// leaf_row_hints), whose misses then overlap the child's own instead of following its box
/// test. Stacked children are not asked for (measured: less gain on the default scene).
struct LeafRowsPrefetch {
    const float* rows;
    void operator()(NodeRef) const {}
    void rows_of_child(const WideNode& node, std::uint32_t /*node_id*/, int slot) const {
        prefetch_rows(rows, node.leaf_row_hints[slot]);
    }
    /// Asks for the lines `hint` names in `rows`.
    static void prefetch_rows(const float* rows, std::uint32_t hint) {
        const std::uint32_t lines = leaf_row_hint_lines(hint);
        // Computed as an integer, so that no pointer past the rows is ever formed; a prefetch
        // never faults.
        const std::uintptr_t first =
            reinterpret_cast<std::uintptr_t>(rows) +
            sizeof(float) * kRowFloatsPerTriangle * std::uintptr_t(hint & NodeRef::kMaxFirst);
        for (std::uint32_t line = 0; line < lines; ++line)
            __builtin_prefetch(reinterpret_cast<const void*>(first + 64 * line));
    }
};

}  // namespace rebraid
