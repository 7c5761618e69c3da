#include "rebraid/rebraiding/rebraid_accel.h"

#include <optional>
#include <utility>
#include <vector>

#include "rebraid/core/build_timer.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/rebraiding/world_space_meshes.h"

namespace rebraid {

InstancedAccel build_rebraid_accel(const Scene& scene, const ObjectBvhBuilder& object_builder,
                                   const RebraidSettings& settings) {
    scene.validate();
    settings.validate();
    const BuildTimer timer;
    const std::optional<Scene> world_space =
        meshes_in_world_space(scene, {.single_instances = settings.world_space_single_instances,
                                      .copy_budget = settings.world_space_copy_budget});
    const Scene& built = world_space ? *world_space : scene;
    std::vector<ObjectBvh> object_bvhs = build_object_bvhs(built, object_builder);
    RebraidBuild build = build_rebraid(built, object_bvhs, settings);
    AccelStats info;
    info.build_ms = timer.elapsed_ms();
    info.top_build_ms = build.top.build_ms;
    info.brefs = build.brefs;
    info.budget = build.budget;
    info.opened = build.opened;
    info.mesh_copies = built.meshes.size() - scene.meshes.size();
    return InstancedAccel(built, std::move(object_bvhs), std::move(build.top), info,
                          settings.merge_settings());
}

}  // namespace rebraid
