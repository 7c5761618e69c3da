#pragma once

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/scene.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid {

/// Object BVHs from `object_builder`, then the re-braided top.
InstancedAccel build_rebraid_accel(
    const Scene& scene, const ObjectBvhBuilder& object_builder = own_object_bvh_builder(),
    const RebraidSettings& settings = {});

}  // namespace rebraid
