#include "rebraid/top_level/instanced_accel.h"

#include <optional>
#include <span>

#include "rebraid/bvh/object_traversal.h"
#include "rebraid/bvh/traversal.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/structure_hash.h"
#include "rebraid/top_level/bvh_stats.h"
#include "rebraid/top_level/two_level_builder.h"

namespace rebraid {

InstancedAccel::InstancedAccel(const Scene& scene, std::vector<ObjectBvh> object_bvhs,
                               TopLevelBvh top, const AccelStats& build_info)
    : object_bvhs_(std::move(object_bvhs)), top_(std::move(top)), build_info_(build_info) {
    instance_mesh_.reserve(scene.instances.size());
    object_to_world_.reserve(scene.instances.size());
    world_to_object_.reserve(scene.instances.size());
    instance_is_identity_.reserve(scene.instances.size());
    for (const Instance& instance : scene.instances) {
        instance_mesh_.push_back(instance.mesh_id);
        object_to_world_.push_back(instance.object_to_world);
        world_to_object_.push_back(instance.object_to_world.inverse());
        instance_is_identity_.push_back(instance.object_to_world == AffineTransform::identity());
    }
    build_info_.triangles = scene.instanced_triangle_count();
    build_info_.instances = scene.instances.size();
    build_info_.meshes = scene.meshes.size();
}

namespace {

/// The ray mapped into the object space of the instance a top-level item names, prepared
/// once per run of items of the same instance (a re-braided top level holds several items per
/// instance, often side by side in one leaf). t is invariant under the affine map, so
/// tnear and tfar carry over unchanged. Instances placed by the identity (objects built in
/// world space, the paper's common case) use the prepared world ray itself: no transform, no
/// reciprocals, no broadcasts, and the same numbers, since the identity maps every finite ray
/// exactly.
class ObjectRayCache {
public:
    ObjectRayCache(PreparedRay& world_ray, std::span<const AffineTransform> world_to_object,
                   std::span<const std::uint8_t> is_identity)
        : world_ray_(world_ray), world_to_object_(world_to_object), is_identity_(is_identity) {}

    PreparedRay& ray_for(InstanceId instance_id) {
        if (is_identity_[instance_id]) return world_ray_;
        const TraversalRay& world = world_ray_.ray;
        if (instance_id != instance_id_) {
            const AffineTransform& to_object = world_to_object_[instance_id];
            ray_.emplace(to_object.transform_point(world.org),
                         to_object.transform_vector(world.dir), world.tnear, world.tfar);
            instance_id_ = instance_id;
        }
        ray_->ray.tnear = world.tnear;
        ray_->ray.tfar = world.tfar;
        return *ray_;
    }

private:
    PreparedRay& world_ray_;
    std::span<const AffineTransform> world_to_object_;
    std::span<const std::uint8_t> is_identity_;
    InstanceId instance_id_ = kInvalidId;
    std::optional<PreparedRay> ray_;
};

}  // namespace

void InstancedAccel::prefetch_item_target(NodeRef leaf) const {
    const TopLevelItem& item = top_.items[leaf.first_prim()];
    const ObjectBvh& bvh = object_bvhs_[instance_mesh_[item.instance_id]];
    if (item.object_node.is_leaf())
        __builtin_prefetch(bvh.triangles.data() + item.object_node.first_prim());
    else
        prefetch_node(bvh.nodes.data(), item.object_node);
}

Hit InstancedAccel::intersect_counted(const Ray& ray, TraversalCounters* counters) const {
    Hit hit;
    PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar);
    ObjectRayCache object_rays(world_ray, world_to_object_, instance_is_identity_);
    const auto enter_items = [&](NodeRef leaf) {
        const std::uint32_t end = leaf.first_prim() + leaf.prim_count();
        for (std::uint32_t i = leaf.first_prim(); i < end; ++i) {
            const TopLevelItem& item = top_.items[i];
            if (counters) ++counters->object_entries;
            PreparedRay& object_ray = object_rays.ray_for(item.instance_id);
            if (intersect_object_bvh(object_bvhs_[instance_mesh_[item.instance_id]],
                                     item.object_node, object_ray, hit, counters)) {
                world_ray.ray.tfar = object_ray.ray.tfar;
                hit.instance_id = item.instance_id;
            }
        }
        return false;
    };
    // A stacked item's object node is asked for as the item is stacked, as a flat BVH's
    // stacked nodes are: its miss then overlaps the work on nearer items.
    const auto prefetch_item = [this](NodeRef leaf) { prefetch_item_target(leaf); };
    traverse_bvh(top_.nodes.data(), top_.root, world_ray, counters, enter_items, prefetch_item);
    return hit;
}

bool InstancedAccel::occluded(const Ray& ray) const {
    PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar);
    ObjectRayCache object_rays(world_ray, world_to_object_, instance_is_identity_);
    // Any order: the first hit ends the query.
    return traverse_bvh<TraversalOrder::any>(
        top_.nodes.data(), top_.root, world_ray, nullptr, [&](NodeRef leaf) {
            const std::uint32_t end = leaf.first_prim() + leaf.prim_count();
            for (std::uint32_t i = leaf.first_prim(); i < end; ++i) {
                const TopLevelItem& item = top_.items[i];
                PreparedRay& object_ray = object_rays.ray_for(item.instance_id);
                if (occluded_object_bvh(object_bvhs_[instance_mesh_[item.instance_id]],
                                        item.object_node, object_ray, nullptr))
                    return true;
            }
            return false;
        });
}

AccelStats InstancedAccel::stats() const {
    AccelStats stats = build_info_;
    stats.sah = top_level_sah(top_, object_bvhs_, instance_mesh_, object_to_world_);
    const TreeCounts top_counts = count_tree(top_.nodes, top_.root);
    std::uint64_t nodes = top_counts.inner_nodes, leaves = 0, memory = top_.memory_bytes();
    StructureHash hash;
    hash.add<WideNode>(top_.nodes);
    hash.add_value(top_.root);
    hash.add<TopLevelItem>(top_.items);
    for (const ObjectBvh& bvh : object_bvhs_) {
        const TreeCounts counts = count_tree(bvh.nodes, bvh.root);
        nodes += counts.inner_nodes;
        leaves += counts.leaves;
        memory += bvh.memory_bytes();
        hash.add<WideNode>(bvh.nodes);
        hash.add_value(bvh.root);
        hash.add<PrimId>(bvh.prim_ids);
    }
    memory += (object_to_world_.size() + world_to_object_.size()) * sizeof(AffineTransform) +
              instance_is_identity_.size();
    stats.nodes = nodes;
    stats.leaves = leaves;
    stats.memory_bytes = memory;
    stats.structure_hash = hash.value();
    return stats;
}

InstancedAccel build_two_level_accel(const Scene& scene, const ObjectBvhBuilder& object_builder,
                                     const BuildSettings& top_settings) {
    scene.validate();
    const BuildTimer timer;
    std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, object_builder);
    TopLevelBvh top = build_two_level(scene, object_bvhs, top_settings);
    AccelStats info;
    info.build_ms = timer.elapsed_ms();
    info.top_build_ms = top.build_ms;
    return InstancedAccel(scene, std::move(object_bvhs), std::move(top), info);
}

}  // namespace rebraid
