#pragma once

#include <cstdint>
#include <span>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// Builds the tree of a re-braided top level again over its final items, by the plain
/// top-level builder (build_top_level_over_items: the top-down SAH build over their world
/// boxes, each weighted by the primitives it stands for, `item_weights[i]` for item i). Opening
/// decides which BRefs there are; the tree it grows on the way made its upper splits over BRefs
/// that were opened only below them, whose children then reach across those splits
/// (RebraidSettings::rebuild_tree). The items keep their content and are reordered into the new
/// leaf order, their `item_bounds` with them. Same tree for any thread count.
void rebuild_top_tree(TopLevelBvh& top, std::span<const std::uint32_t> item_weights,
                      const BuildSettings& settings);

}  // namespace rebraid
