#include "rebraid/dynamic/dynamic_scene.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "rebraid/core/error.h"
#include "rebraid/core/random.h"

namespace rebraid {

void DynamicPlacementSettings::validate() const {
    if (copy_count == 0) throw Error("DynamicPlacementSettings: copy_count must be at least 1");
    if (!(size_fraction > 0.0f && size_fraction <= 1.0f))
        throw Error("DynamicPlacementSettings: size_fraction " + std::to_string(size_fraction) +
                    " must be in (0, 1]");
}

namespace {

float largest_extent(const BBox3f& bounds) {
    const Vec3f extent = bounds.extent();
    return std::max({extent.x, extent.y, extent.z});
}

/// Object space of the animated object -> world for copy `copy_id` of `copy_count`.
AffineTransform copy_placement(const BBox3f& static_bounds, const BBox3f& object_bounds,
                               std::size_t copy_id, const DynamicPlacementSettings& settings,
                               Random& random) {
    const Vec3f extent = static_bounds.extent();
    // Side by side along the longer horizontal axis, over its middle 60%.
    const int along = extent.x >= extent.z ? 0 : 2;
    const int across = 2 - along;
    const float slot = 0.6f / static_cast<float>(settings.copy_count);
    const float jitter_along = (random.next_float01() - 0.5f) * 0.5f * slot;
    const float jitter_across = (random.next_float01() - 0.5f) * 0.2f;
    const float turn = random.next_float01() * 2.0f * std::numbers::pi_v<float>;
    Vec3f spot = static_bounds.center();
    spot[along] =
        static_bounds.min[along] +
        extent[along] * (0.2f + slot * (static_cast<float>(copy_id) + 0.5f) + jitter_along);
    spot[across] += extent[across] * jitter_across;

    const float object_size = std::max(largest_extent(object_bounds), 1e-30f);
    const float scale =
        settings.size_fraction * std::max(largest_extent(static_bounds), 1e-6f) / object_size;
    // The object's bottom centre goes to the spot.
    const Vec3f anchor{object_bounds.center().x, object_bounds.min.y, object_bounds.center().z};
    return AffineTransform::translate(spot) * AffineTransform::rotate({0.0f, 1.0f, 0.0f}, turn) *
           AffineTransform::scale({scale, scale, scale}) * AffineTransform::translate(-anchor);
}

}  // namespace

DynamicScene::DynamicScene(const Scene& static_scene, const AnimatedObject& object,
                           const DynamicPlacementSettings& settings)
    : object_(object), scene_(static_scene) {
    settings.validate();
    static_scene.validate();
    const Scene& rest = object.rest_scene();
    if (rest.instanced_triangle_count() == 0)
        throw Error("DynamicScene: the animated object has no triangles");
    static_mesh_count_ = static_scene.meshes.size();
    static_instance_count_ = static_scene.instances.size();
    // An empty static scene still gets a stage of the object's size.
    BBox3f static_bounds =
        static_scene.instanced_triangle_count() > 0 ? static_scene.bounds() : rest.bounds();
    const BBox3f object_bounds = rest.bounds();

    Random random(settings.seed);
    for (std::size_t copy_id = 0; copy_id < settings.copy_count; ++copy_id) {
        Copy copy;
        copy.posed = rest;
        copy.placement = copy_placement(static_bounds, object_bounds, copy_id, settings, random);
        copy.time_shift = object.duration() * static_cast<float>(copy_id) /
                          static_cast<float>(settings.copy_count);
        const auto mesh_offset = static_cast<MeshId>(scene_.meshes.size());
        const auto instance_offset = static_cast<InstanceId>(scene_.instances.size());
        for (const Mesh& mesh : rest.meshes) scene_.meshes.push_back(mesh);
        for (const Instance& instance : rest.instances)
            scene_.instances.push_back(
                {instance.mesh_id + mesh_offset, copy.placement * instance.object_to_world});
        for (MeshId mesh_id : object.deformed_meshes())
            dynamic_meshes_.push_back(mesh_id + mesh_offset);
        for (InstanceId instance_id : object.moving_instances())
            moving_instances_.push_back(instance_id + instance_offset);
        copies_.push_back(std::move(copy));
    }
    is_dynamic_mesh_.assign(scene_.meshes.size(), 0);
    for (MeshId mesh_id : dynamic_meshes_) is_dynamic_mesh_[mesh_id] = 1;
    std::vector<char> is_moving(scene_.instances.size(), 0);
    for (InstanceId instance_id : moving_instances_) is_moving[instance_id] = 1;
    for (std::size_t i = 0; i < scene_.instances.size(); ++i)
        if (is_moving[i] || is_dynamic_mesh_[scene_.instances[i].mesh_id])
            changing_instances_.push_back(static_cast<InstanceId>(i));
    pose(0.0f);
    scene_.validate();
}

void DynamicScene::pose(float time) {
    const Scene& rest = object_.rest_scene();
    for (std::size_t copy_id = 0; copy_id < copies_.size(); ++copy_id) {
        Copy& copy = copies_[copy_id];
        object_.pose(time + copy.time_shift, copy.posed);
        const std::size_t mesh_offset = static_mesh_count_ + copy_id * rest.meshes.size();
        const std::size_t instance_offset =
            static_instance_count_ + copy_id * rest.instances.size();
        // Copied, not swapped: the posed scene stays whole for the next pose.
        for (MeshId mesh_id : object_.deformed_meshes()) {
            const std::vector<Vec3f>& posed = copy.posed.meshes[mesh_id].positions;
            std::copy(posed.begin(), posed.end(),
                      scene_.meshes[mesh_offset + mesh_id].positions.begin());
        }
        for (InstanceId instance_id : object_.moving_instances())
            scene_.instances[instance_offset + instance_id].object_to_world =
                copy.placement * copy.posed.instances[instance_id].object_to_world;
    }
}

}  // namespace rebraid
