#pragma once

#include <cstdint>
#include <limits>

#include "rebraid/core/bbox.h"

namespace rebraid {

/// Branching factor of every BVH in the project (object, flat and top level share the layout,
/// so one traversal kernel serves all). 8 matches one AVX2 register of floats per bound plane.
inline constexpr int kBvhWidth = 8;

/// Most primitives (triangles or top-level items) one leaf reference can hold.
inline constexpr std::uint32_t kMaxLeafSize = 16;

/// A 32-bit child reference. Inner node: its index in the BVH's node array. Leaf: the range of
/// primitives [first, first + count) in the BVH's leaf order. A reference can name any node of
/// any BVH, which is what lets a top-level leaf start traversal deep inside an object BVH.
class NodeRef {
public:
    static constexpr std::uint32_t kLeafBit = 0x80000000u;
    static constexpr int kCountShift = 27;
    static constexpr std::uint32_t kMaxFirst = (1u << kCountShift) - 1;
    static constexpr std::uint32_t kEmptyBits = 0x7fffffffu;

    constexpr NodeRef() = default;
    static constexpr NodeRef inner(std::uint32_t node_id) { return NodeRef(node_id); }
    /// Precondition: first <= kMaxFirst, 1 <= count <= kMaxLeafSize.
    static constexpr NodeRef leaf(std::uint32_t first, std::uint32_t count) {
        return NodeRef(kLeafBit | ((count - 1) << kCountShift) | first);
    }
    static constexpr NodeRef empty() { return NodeRef(kEmptyBits); }

    constexpr bool is_empty() const { return bits_ == kEmptyBits; }
    constexpr bool is_leaf() const { return (bits_ & kLeafBit) != 0; }
    // Inner ids lie below kEmptyBits, leaves (top bit set) above: one compare.
    constexpr bool is_inner() const { return bits_ < kEmptyBits; }
    constexpr std::uint32_t node_id() const { return bits_; }
    constexpr std::uint32_t first_prim() const { return bits_ & kMaxFirst; }
    constexpr std::uint32_t prim_count() const { return ((bits_ >> kCountShift) & 0xfu) + 1; }
    constexpr std::uint32_t bits() const { return bits_; }
    friend constexpr bool operator==(NodeRef, NodeRef) = default;

private:
    constexpr explicit NodeRef(std::uint32_t bits) : bits_(bits) {}
    std::uint32_t bits_ = kEmptyBits;
};

/// An inner node: the boxes of up to kBvhWidth children stored plane by plane (structure of
/// arrays), so testing a ray against all children is six vector loads and a few min/max ops.
/// Unused slots hold an empty box (lower = +inf, upper = -inf) that no ray can hit, and
/// NodeRef::empty(). Used slots come first. Padded to four whole cache lines: the six planes
/// then always sit on three lines (224 bytes at 32-byte alignment put half the nodes' planes
/// on four), and a node's address is its index shifted, not multiplied.
struct alignas(64) WideNode {
    float lower_x[kBvhWidth], upper_x[kBvhWidth];
    float lower_y[kBvhWidth], upper_y[kBvhWidth];
    float lower_z[kBvhWidth], upper_z[kBvhWidth];
    NodeRef children[kBvhWidth];
    /// Per inner child, where its leaf children's rows start (leaf_row_hints.h), else 0;
    /// written for object BVHs with leaf rows, zero elsewhere (zeroed so that equal nodes
    /// compare equal bytewise). Object nodes copied into a merged top level keep their
    /// source's index in their leaf slots' words (MergedTopLevel::source_of_leaves).
    std::uint32_t leaf_row_hints[kBvhWidth] = {};

    /// A node with every slot unused.
    static WideNode make_empty() {
        WideNode node;
        for (int i = 0; i < kBvhWidth; ++i) node.set_child(i, NodeRef::empty(), BBox3f{});
        return node;
    }
    void set_child(int slot, NodeRef ref, const BBox3f& box) {
        lower_x[slot] = box.min.x, lower_y[slot] = box.min.y, lower_z[slot] = box.min.z;
        upper_x[slot] = box.max.x, upper_y[slot] = box.max.y, upper_z[slot] = box.max.z;
        children[slot] = ref;
    }
    BBox3f child_bounds(int slot) const {
        return {{lower_x[slot], lower_y[slot], lower_z[slot]},
                {upper_x[slot], upper_y[slot], upper_z[slot]}};
    }
    int child_count() const {
        int count = 0;
        while (count < kBvhWidth && !children[count].is_empty()) ++count;
        return count;
    }
    BBox3f bounds() const {
        BBox3f box;
        for (int i = 0; i < kBvhWidth && !children[i].is_empty(); ++i) box.extend(child_bounds(i));
        return box;
    }
};
static_assert(sizeof(WideNode) == 256, "six planes of 8 floats, 8 references and padding");

}  // namespace rebraid

namespace rebraid {

/// Wide levels a builder may grow with SAH splits; deeper, it splits ranges by index.
inline constexpr int kSahDepthLimit = 40;
/// Deepest wide-node nesting any builder produces (object, flat or top level alone): index
/// splits halve ranges of at most 2^27 prims, so they add at most 28 levels.
inline constexpr int kMaxBvhDepth = kSahDepthLimit + 28;

}  // namespace rebraid
