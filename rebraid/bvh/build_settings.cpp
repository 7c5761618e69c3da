#include "rebraid/bvh/build_settings.h"

#include <cmath>
#include <string>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/error.h"

namespace rebraid {

void BuildSettings::validate() const {
    if (bin_count < 2 || bin_count > 256)
        throw Error("BuildSettings: bin_count " + std::to_string(bin_count) + " is outside 2..256");
    if (max_leaf_size < 1 || max_leaf_size > kMaxLeafSize)
        throw Error("BuildSettings: max_leaf_size " + std::to_string(max_leaf_size) +
                    " is outside 1.." + std::to_string(kMaxLeafSize));
    if (!(traversal_cost >= 0.0f) || !std::isfinite(traversal_cost))
        throw Error("BuildSettings: traversal_cost " + std::to_string(traversal_cost) +
                    " must be finite and >= 0");
    if (!(intersection_cost > 0.0f) || !std::isfinite(intersection_cost))
        throw Error("BuildSettings: intersection_cost " + std::to_string(intersection_cost) +
                    " must be finite and > 0");
    if (parallel_threshold < 64)
        throw Error("BuildSettings: parallel_threshold " + std::to_string(parallel_threshold) +
                    " must be >= 64");
    if (prims_per_bin < 1)
        throw Error("BuildSettings: prims_per_bin " + std::to_string(prims_per_bin) +
                    " must be >= 1");
    if (max_children < 2 || max_children > std::uint32_t(kBvhWidth))
        throw Error("BuildSettings: max_children " + std::to_string(max_children) +
                    " is outside 2.." + std::to_string(kBvhWidth));
    if (collapse != NodeCollapse::greedy && collapse != NodeCollapse::optimal)
        throw Error("BuildSettings: collapse " + std::to_string(int(collapse)) +
                    " is neither greedy nor optimal");
    if (fill_nodes && collapse != NodeCollapse::greedy)
        throw Error(
            "BuildSettings: fill_nodes needs collapse greedy (the optimal collapse keeps "
            "the SAH's leaves)");
    if (!(spatial_split_budget >= 0.0f) || !(spatial_split_budget <= 4.0f))
        throw Error("BuildSettings: spatial_split_budget " + std::to_string(spatial_split_budget) +
                    " is outside 0..4");
    if (spatial_split_budget > 0.0f && collapse != NodeCollapse::optimal)
        throw Error("BuildSettings: spatial_split_budget needs collapse optimal");
    if (task_threshold < 1)
        throw Error("BuildSettings: task_threshold " + std::to_string(task_threshold) +
                    " must be >= 1");
}

}  // namespace rebraid
