#pragma once

#include <cstdint>
#include <span>

#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// The SAH cost (in half-area units, before dividing by the root's area) of a re-braided
/// top level, up to a constant that depends only on the instances, so two builds over the
/// same instances compare exactly without walking the object BVHs:
///
///   cost = Σ top inner nodes A(node) + Σ items (A(item box) · k(item) - node_cost(item))
///          - Σ removed_cost,
///
/// where k is the item's triangle count for a leaf and 1 for an inner node, node_cost is
/// what the item's object node costs inside its instance (mapped half area times k; 0 for a
/// triangle of an opened leaf) and removed_cost sums node_cost over every opened BRef. The
/// full SAH adds, per instance, the mapped cost of all its object nodes (the constant):
/// each item's box replaces its node's mapped box, and an opened node is not visited at all.
/// `item_slots[i]` is item i's index into `node_cost`; `removed_cost` is summed in order.
double cost_above_objects(const TopLevelBvh& top, std::span<const std::uint32_t> item_slots,
                          std::span<const double> node_cost, std::span<const double> removed_cost);

/// The part of that cost the top level's own nodes and boxes make: Σ top inner nodes
/// A(node) + Σ items A(item box) · k(item), without the object terms. The budget search
/// measures a doubling's gain against it.
double top_level_own_cost(const TopLevelBvh& top);

}  // namespace rebraid
