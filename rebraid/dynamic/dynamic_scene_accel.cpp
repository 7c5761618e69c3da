#include "rebraid/dynamic/dynamic_scene_accel.h"

#include <tbb/parallel_for.h>

#include <string>
#include <utility>

#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"
#include "rebraid/rebraiding/rebraid_builder.h"

namespace rebraid {

std::string_view dynamic_top_name(DynamicTop top) {
    switch (top) {
        case DynamicTop::two_level:
            return "twolevel";
        case DynamicTop::rebraid:
            return "rebraid";
        case DynamicTop::rebraid_incremental:
            return "rebraid-incremental";
    }
    return "unknown";
}

DynamicTop parse_dynamic_top(std::string_view name) {
    for (DynamicTop top :
         {DynamicTop::two_level, DynamicTop::rebraid, DynamicTop::rebraid_incremental})
        if (name == dynamic_top_name(top)) return top;
    throw Error("unknown top level '" + std::string(name) +
                "' (valid: twolevel, rebraid, rebraid-incremental)");
}

namespace {

/// Per instance: 1 when it neither moves nor shows a deforming mesh (its SAH costs last).
std::vector<char> fixed_instances(const DynamicScene& scene) {
    std::vector<char> is_fixed(scene.scene().instances.size(), 1);
    for (InstanceId id : scene.changing_instances()) is_fixed[id] = 0;
    return is_fixed;
}

}  // namespace

DynamicSceneAccel::DynamicSceneAccel(const DynamicScene& scene,
                                     const DynamicSceneAccelSettings& settings)
    : scene_(scene), settings_(settings), sah_cache_(fixed_instances(scene)) {
    settings_.update.validate();
    settings_.static_build.validate();
    settings_.two_level_top.validate();
    settings_.rebraid.validate();
    settings_.incremental.validate();
    const BuildTimer timer;
    const Scene& world = scene.scene();
    updaters_.reserve(scene.dynamic_meshes().size());
    for (std::size_t i = 0; i < scene.dynamic_meshes().size(); ++i)
        updaters_.emplace_back(settings_.update);
    last_updates_.assign(updaters_.size(), {});

    // Dynamic meshes start from the tree their updater rebuilds to (one primitive per leaf
    // when it rotates), so the first frame compares like with like.
    const BuildSettings dynamic_build =
        updaters_.empty() ? settings_.static_build : updaters_.front().rebuild_settings();
    std::vector<ObjectBvh> object_bvhs(world.meshes.size());
    tbb::parallel_for(std::size_t(0), world.meshes.size(), std::size_t(1), [&](std::size_t i) {
        const Mesh& mesh = world.meshes[i];
        if (scene.is_dynamic_mesh(MeshId(i)))
            object_bvhs[i] = build_object_bvh(mesh, dynamic_build);
        else if (settings_.static_builder)
            object_bvhs[i] = settings_.static_builder(mesh);
        else
            object_bvhs[i] = build_object_bvh(mesh, settings_.static_build);
    });
    if (settings_.top == DynamicTop::rebraid_incremental) {
        // Static: instances that neither move nor show a deforming mesh, whichever part of
        // the composed scene they came from.
        changing_instances_ = scene.changing_instances();
        std::vector<InstanceId> static_instances;
        static_instances.reserve(world.instances.size() - changing_instances_.size());
        std::size_t next_changing = 0;
        for (std::size_t i = 0; i < world.instances.size(); ++i) {
            if (next_changing < changing_instances_.size() &&
                changing_instances_[next_changing] == i) {
                ++next_changing;
                continue;
            }
            static_instances.push_back(InstanceId(i));
        }
        incremental_.emplace(settings_.rebraid, settings_.incremental);
        incremental_->build_static(world, object_bvhs, static_instances);
    }
    assemble(std::move(object_bvhs));
    build_ms_ = timer.elapsed_ms();
}

void DynamicSceneAccel::assemble(std::vector<ObjectBvh> object_bvhs, TopLevelBvh previous) {
    const Scene& world = scene_.scene();
    const BuildTimer timer;
    // The last structure's object BVHs were moved out already; freeing its top level before
    // the next is built lets the allocator hand the same (already mapped) memory back.
    accel_.reset();
    AccelStats info;
    TopLevelBvh top;
    if (settings_.top == DynamicTop::rebraid) {
        RebraidBuild build = build_rebraid(world, object_bvhs, settings_.rebraid);
        top = std::move(build.top);
        info.brefs = build.brefs;
        info.budget = build.budget;
        info.opened = build.opened;
    } else if (settings_.top == DynamicTop::rebraid_incremental) {
        last_incremental_ =
            incremental_->build_frame(world, object_bvhs, changing_instances_, std::move(previous));
        top = std::move(last_incremental_.top);
        last_incremental_.top = {};
        info.brefs = last_incremental_.brefs;
        info.budget = last_incremental_.budget;
        info.opened = last_incremental_.opened;
    } else {
        top = build_two_level(world, object_bvhs, settings_.two_level_top);
    }
    info.top_build_ms = timer.elapsed_ms();
    accel_.emplace(world, std::move(object_bvhs), std::move(top), info);
}

DynamicFrameReport DynamicSceneAccel::update() {
    DynamicFrameReport report;
    const Scene& world = scene_.scene();
    // An incremental top that was not a full re-braid starts with the static top, which the
    // next frame keeps: its arrays are reused instead of copying the static part again.
    TopLevelBvh previous_top;
    if (settings_.top == DynamicTop::rebraid_incremental && !last_incremental_.is_full_rebraid)
        previous_top = std::move(*accel_).release_top_level();
    std::vector<ObjectBvh> object_bvhs = std::move(*accel_).release_object_bvhs();
    {
        const BuildTimer timer;
        const std::vector<MeshId>& dynamic = scene_.dynamic_meshes();
        // Each updater owns its mesh's tree: the meshes are independent, so the order in
        // which they finish does not matter.
        tbb::parallel_for(std::size_t(0), dynamic.size(), std::size_t(1), [&](std::size_t i) {
            last_updates_[i] =
                updaters_[i].update(world.meshes[dynamic[i]], object_bvhs[dynamic[i]]);
        });
        report.update_ms = timer.elapsed_ms();
    }
    {
        const BuildTimer timer;
        assemble(std::move(object_bvhs), std::move(previous_top));
        report.top_ms = timer.elapsed_ms();
    }
    {
        // Outside both timed parts: the SAH is reported, not needed by the frame. Static
        // instances' items cost the same every frame, so only the others are recomputed.
        transforms_.resize(world.instances.size());
        for (std::size_t i = 0; i < world.instances.size(); ++i)
            transforms_[i] = world.instances[i].object_to_world;
        report.sah = sah_cache_.sah(accel_->top_level(), accel_->object_bvhs(),
                                    accel_->instance_meshes(), transforms_);
    }
    return report;
}

}  // namespace rebraid
