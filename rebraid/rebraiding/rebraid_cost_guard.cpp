#include "rebraid/rebraiding/rebraid_cost_guard.h"

namespace rebraid {

namespace {

/// Σ top inner nodes A(node) + Σ items item_term(i, A(item box) · k(item)), in array order.
template <class ItemTerm>
double sum_over_top(const TopLevelBvh& top, ItemTerm&& item_term) {
    double cost = top.root.is_inner() ? double(top.bounds.half_area()) : 0.0;
    for (const WideNode& node : top.nodes)
        for (int c = 0; c < kBvhWidth && !node.children[c].is_empty(); ++c)
            if (node.children[c].is_inner()) cost += node.child_bounds(c).half_area();
    for (std::size_t i = 0; i < top.items.size(); ++i) {
        const NodeRef node = top.items[i].object_node;
        const double k = node.is_leaf() ? node.prim_count() : 1.0;
        cost += item_term(i, double(top.item_bounds[i].half_area()) * k);
    }
    return cost;
}

}  // namespace

double cost_above_objects(const TopLevelBvh& top, std::span<const std::uint32_t> item_slots,
                          std::span<const double> node_cost, std::span<const double> removed_cost) {
    double cost = sum_over_top(
        top, [&](std::size_t i, double box_cost) { return box_cost - node_cost[item_slots[i]]; });
    for (const double removed : removed_cost) cost -= removed;
    return cost;
}

double top_level_own_cost(const TopLevelBvh& top) {
    return sum_over_top(top, [](std::size_t, double box_cost) { return box_cost; });
}

}  // namespace rebraid
