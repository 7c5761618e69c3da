#include "rebraid/rebraiding/bref_budget.h"

#include <algorithm>
#include <cmath>

namespace rebraid {

std::uint64_t bref_budget(const RebraidSettings& settings, std::uint64_t instance_count,
                          std::uint64_t instanced_primitive_count) {
    const auto per_instance =
        std::uint64_t(std::floor(double(settings.budget_factor) * double(instance_count)));
    const auto per_primitive =
        std::uint64_t(double(instanced_primitive_count) / double(settings.primitives_per_bref));
    std::uint64_t budget = 0;
    switch (settings.budget_rule) {
        case BudgetRule::per_instance:
            budget = per_instance;
            break;
        case BudgetRule::per_primitive:
            budget = per_primitive;
            break;
        case BudgetRule::larger:
            budget = std::max(per_instance, per_primitive);
            break;
    }
    const std::uint64_t openable =
        instanced_primitive_count > instance_count ? instanced_primitive_count - instance_count : 0;
    return std::min({budget, openable, settings.max_budget});
}

std::pair<BRefSegment, BRefSegment> split_free_space(const BRefSegment& parent, std::uint32_t mid,
                                                     std::uint32_t left_openable,
                                                     std::uint32_t right_openable,
                                                     std::span<BuildPrim> prims) {
    const std::uint64_t space = parent.free_space();
    std::uint64_t left_weight = left_openable, right_weight = right_openable;
    if (left_weight + right_weight == 0) {
        left_weight = mid - parent.start;
        right_weight = parent.end - mid;
    }
    const auto left_space = std::uint32_t(space * left_weight / (left_weight + right_weight));

    // Move the right BRefs left_space slots to the right. Only the first min(left_space,
    // right count) of them need to move: they go to the slots past the old end.
    const std::uint32_t right_count = parent.end - mid;
    const std::uint32_t moved = std::min(left_space, right_count);
    const std::uint32_t destination = std::max(parent.end, mid + left_space);
    std::copy(prims.begin() + mid, prims.begin() + mid + moved, prims.begin() + destination);

    const BRefSegment left{parent.start,     mid,
                           mid + left_space, parent.next_target,
                           parent.can_open,  parent.failed_estimates};
    const BRefSegment right{mid + left_space, parent.end + left_space,
                            parent.end_extra, parent.next_target + left_space,
                            parent.can_open,  parent.failed_estimates};
    return {left, right};
}

}  // namespace rebraid
