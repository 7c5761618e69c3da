#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/scene.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// What the incremental top level reads of a static top again and again, computed once per
/// static top: per node the triangles below it (the SAH weight of the node as one piece of a
/// cut) and its height (to keep grafted trees within the traversal's depth limit).
struct StaticTopSummary {
    std::vector<std::uint64_t> item_prims;   ///< index = item of the static top
    std::vector<std::uint64_t> node_prims;   ///< index = node of the static top
    std::vector<std::uint32_t> node_height;  ///< wide levels from the node down, >= 1

    /// Triangles below a reference of the static top (node or leaf range of items).
    std::uint64_t prims_of(NodeRef ref) const;
    /// Wide levels from `ref` down: 0 for a leaf range, node_height for a node.
    std::uint32_t height_of(NodeRef ref) const {
        return ref.is_inner() ? node_height[ref.node_id()] : 0;
    }
};

/// Summarises `top`, a top level over instances of `scene` with these object BVHs.
StaticTopSummary summarize_static_top(const TopLevelBvh& top, const Scene& scene,
                                      std::span<const ObjectBvh> object_bvhs);

/// One piece of a cut through a static top: a subtree (inner node or leaf range of items)
/// that the frame's top level keeps whole, with its box as the static top stores it.
struct StaticTopPiece {
    NodeRef ref;
    BBox3f bounds;
};

/// A cut through a static top: every item is below exactly one piece.
struct StaticTopCut {
    std::vector<StaticTopPiece> pieces;  ///< in the order they were reached
    std::uint32_t opened_nodes = 0;      ///< nodes of the static top replaced by children
};

/// The cut the frame's top level is built over: starting from the root of `static_top`, the
/// piece of largest surface area whose box overlaps the box of a leaf of `dynamic_top` is
/// replaced by its children, while the cut stays within `max_piece_count` pieces (ties of
/// area go to the lower node id, so the cut does not depend on anything but its inputs).
/// Pieces that overlap nothing dynamic keep their subtree, built once, as it is; near the
/// dynamic objects the cut reaches the static items, so a new SAH build can interleave them
/// with the dynamic BRefs as a full re-braid would.
StaticTopCut cut_static_top(const TopLevelBvh& static_top, const TopLevelBvh& dynamic_top,
                            std::uint32_t max_piece_count);

}  // namespace rebraid
