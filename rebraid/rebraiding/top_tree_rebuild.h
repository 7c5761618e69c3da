#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// The SAH weight of a BRef of `primitives` triangles in the rebuilt tree:
/// 1 + floor(log2(primitives)). A ray that enters a BRef's box pays for its object subtree's
/// depth and a leaf or two, which grow with the logarithm of its triangles, not with their
/// number; weighing BRefs by their counts (the rule of the tree grown while opening, §4.3)
/// keeps large BRefs apart at the price of node visits elsewhere. Measured against the counts
/// (docs/design.md): fewer node visits per diffuse ray on every scene that opens but
/// motion_capture_rom (fzk_haus 4.26 to 3.93, crown 9.38 to 9.22).
constexpr std::uint32_t rebuilt_tree_weight(std::uint32_t primitives) {
    return std::max(1u, std::uint32_t(std::bit_width(primitives)));
}

/// Builds the tree of a re-braided top level again over its final items, by the plain
/// top-level builder (build_top_level_over_items: the top-down SAH build over their world
/// boxes), each weighted by rebuilt_tree_weight of the primitives it stands for
/// (`item_primitives[i]` for item i). Opening decides which BRefs there are; the tree it grows
/// on the way made its upper splits over BRefs that were opened only below them, whose
/// children then reach across those splits (RebraidSettings::rebuild_tree). The items keep
/// their content and are reordered into the new leaf order, their `item_bounds` with them.
/// Same tree for any thread count.
void rebuild_top_tree(TopLevelBvh& top, std::span<const std::uint32_t> item_primitives,
                      const BuildSettings& settings);

}  // namespace rebraid
