#include "rebraid/rebraid_settings.h"

#include <cmath>
#include <string>

#include "rebraid/error.h"
#include "rebraid/wide_node.h"

namespace rebraid {

void RebraidSettings::validate() const {
    auto check = [](bool ok, const char* field, float value, const char* rule) {
        if (!ok)
            throw Error(std::string("RebraidSettings: ") + field + " " + std::to_string(value) +
                        " " + rule);
    };
    check(std::isfinite(open_threshold) && open_threshold >= 0.0f, "open_threshold", open_threshold,
          "must be finite and >= 0");
    check(std::isfinite(budget_factor) && budget_factor >= 0.0f && budget_factor <= 1e6f,
          "budget_factor", budget_factor, "must be finite and in [0, 1e6]");
    check(std::isfinite(primitives_per_bref) && primitives_per_bref >= 1.0f, "primitives_per_bref",
          primitives_per_bref, "must be finite and >= 1");
    if (max_budget > NodeRef::kMaxFirst)
        throw Error("RebraidSettings: max_budget " + std::to_string(max_budget) +
                    " must be at most " + std::to_string(NodeRef::kMaxFirst));
    check(std::isfinite(small_overlap_fraction) && small_overlap_fraction >= 0.0f,
          "small_overlap_fraction", small_overlap_fraction, "must be finite and >= 0");
    build.validate();
}

}  // namespace rebraid
