#include "rebraid/rebraiding/rebraid_settings.h"

#include <cmath>
#include <sstream>
#include <string>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/error.h"

namespace rebraid {

void RebraidSettings::validate() const {
    auto check = [](bool ok, const char* field, float value, const char* rule) {
        if (!ok) {
            std::ostringstream text;  // "-1", not "-1.000000"
            text << "re-braiding setting " << field << " " << value << " " << rule;
            throw Error(text.str());
        }
    };
    check(std::isfinite(open_threshold) && open_threshold >= 0.0f, "open_threshold", open_threshold,
          "must be finite and >= 0");
    check(std::isfinite(budget_factor) && budget_factor >= 0.0f && budget_factor <= 1e6f,
          "budget_factor", budget_factor, "must be finite and in [0, 1e6]");
    check(std::isfinite(primitives_per_bref) && primitives_per_bref >= 1.0f, "primitives_per_bref",
          primitives_per_bref, "must be finite and >= 1");
    if (max_budget > NodeRef::kMaxFirst)
        throw Error("re-braiding setting max_budget " + std::to_string(max_budget) +
                    " must be at most " + std::to_string(NodeRef::kMaxFirst));
    check(std::isfinite(small_overlap_fraction) && small_overlap_fraction >= 0.0f,
          "small_overlap_fraction", small_overlap_fraction, "must be finite and >= 0");
    check(std::isfinite(instance_entry_cost) && instance_entry_cost >= 0.0f, "instance_entry_cost",
          instance_entry_cost, "must be finite and >= 0");
    check(std::isfinite(overlap_threshold) && overlap_threshold >= 0.0f, "overlap_threshold",
          overlap_threshold, "must be finite and >= 0");
    if (budget_doublings > kMaxBudgetDoublings)
        throw Error("re-braiding setting budget_doublings " + std::to_string(budget_doublings) +
                    " must be at most " + std::to_string(kMaxBudgetDoublings));
    check(std::isfinite(budget_search_min_gain) && budget_search_min_gain >= 0.0f &&
              budget_search_min_gain < 1.0f,
          "budget_search_min_gain", budget_search_min_gain, "must be finite and in [0, 1)");
    check(std::isfinite(world_space_copy_budget) && world_space_copy_budget >= 0.0f,
          "world_space_copy_budget", world_space_copy_budget, "must be finite and >= 0");
    check(std::isfinite(merge_placed_node_budget) && merge_placed_node_budget >= 0.0f,
          "merge_placed_node_budget", merge_placed_node_budget, "must be finite and >= 0");
    check(merge_items_out_of_line_area_share >= 0.0f, "merge_items_out_of_line_area_share",
          merge_items_out_of_line_area_share, "must be >= 0 (infinity: always)");
    check(std::isfinite(world_tree_triangle_budget) && world_tree_triangle_budget >= 0.0f,
          "world_tree_triangle_budget", world_tree_triangle_budget, "must be finite and >= 0");
    check(world_tree_spatial_split_budget >= 0.0f && world_tree_spatial_split_budget <= 4.0f,
          "world_tree_spatial_split_budget", world_tree_spatial_split_budget, "must be in [0, 4]");
    check(std::isfinite(budget_search_extra_gain) && budget_search_extra_gain >= 0.0f,
          "budget_search_extra_gain", budget_search_extra_gain, "must be finite and >= 0");
    check(std::isfinite(budget_search_min_use) && budget_search_min_use >= 0.0f &&
              budget_search_min_use <= 1.0f,
          "budget_search_min_use", budget_search_min_use, "must be finite and in [0, 1]");
    if (estimate_levels > 8)
        throw Error("re-braiding setting estimate_levels " + std::to_string(estimate_levels) +
                    " must be at most 8");
    if (world_space_estimate_levels > 8)
        throw Error("re-braiding setting world_space_estimate_levels " +
                    std::to_string(world_space_estimate_levels) + " must be at most 8");
    if (opening_rule != OpeningRule::extent && opening_rule != OpeningRule::sah &&
        opening_rule != OpeningRule::overlap)
        throw Error("re-braiding setting opening_rule " + std::to_string(int(opening_rule)) +
                    " is not an OpeningRule");
    build.validate();
}

}  // namespace rebraid
