#pragma once
// The project's own structures over one scene, for tests that check each of them the same way.

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid::test {

/// Structures named as the command line names them.
using NamedAccels = std::vector<std::pair<std::string, std::unique_ptr<Accel>>>;

/// `flat`, `twolevel` and `rebraid` (default settings) built over `scene`, and
/// `rebraid-open-everything`: threshold 0 and `open_everything_budget` extra BRefs per
/// instance, which opens as deep as the object BVHs go.
inline NamedAccels own_structures(const Scene& scene, float open_everything_budget) {
    NamedAccels structures;
    structures.emplace_back("flat", std::make_unique<FlatAccel>(scene));
    structures.emplace_back("twolevel",
                            std::make_unique<InstancedAccel>(build_two_level_accel(scene)));
    structures.emplace_back("rebraid",
                            std::make_unique<InstancedAccel>(build_rebraid_accel(scene)));
    structures.emplace_back(
        "rebraid-open-everything",
        std::make_unique<InstancedAccel>(build_rebraid_accel(
            scene, own_object_bvh_builder(),
            {.open_threshold = 0.0f, .budget_factor = open_everything_budget})));
    return structures;
}

}  // namespace rebraid::test
