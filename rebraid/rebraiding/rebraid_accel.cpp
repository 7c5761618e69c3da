#include "rebraid/rebraiding/rebraid_accel.h"

#include <utility>
#include <vector>

#include "rebraid/core/build_timer.h"
#include "rebraid/rebraiding/rebraid_builder.h"

namespace rebraid {

InstancedAccel build_rebraid_accel(const Scene& scene, const ObjectBvhBuilder& object_builder,
                                   const RebraidSettings& settings) {
    scene.validate();
    settings.validate();
    const BuildTimer timer;
    std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, object_builder);
    RebraidBuild build = build_rebraid(scene, object_bvhs, settings);
    AccelStats info;
    info.build_ms = timer.elapsed_ms();
    info.top_build_ms = build.top.build_ms;
    info.brefs = build.brefs;
    info.budget = build.budget;
    info.opened = build.opened;
    return InstancedAccel(scene, std::move(object_bvhs), std::move(build.top), info,
                          settings.merge_world_space);
}

}  // namespace rebraid
