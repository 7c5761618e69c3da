#include "rebraid/rebraiding/rebraid_cost_guard.h"

namespace rebraid {

double cost_above_objects(const TopLevelBvh& top, std::span<const std::uint32_t> item_slots,
                          std::span<const double> node_cost, std::span<const double> removed_cost) {
    double cost = top.root.is_inner() ? double(top.bounds.half_area()) : 0.0;
    for (const WideNode& node : top.nodes)
        for (int c = 0; c < kBvhWidth && !node.children[c].is_empty(); ++c)
            if (node.children[c].is_inner()) cost += node.child_bounds(c).half_area();
    for (std::size_t i = 0; i < top.items.size(); ++i) {
        const NodeRef node = top.items[i].object_node;
        const double k = node.is_leaf() ? node.prim_count() : 1.0;
        cost += double(top.item_bounds[i].half_area()) * k - node_cost[item_slots[i]];
    }
    for (const double removed : removed_cost) cost -= removed;
    return cost;
}

}  // namespace rebraid
