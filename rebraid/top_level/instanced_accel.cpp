#include "rebraid/top_level/instanced_accel.h"

#include <array>
#include <cstring>
#include <string>
#include <unordered_map>

#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"
#include "rebraid/core/structure_hash.h"
#include "rebraid/top_level/bvh_stats.h"
#include "rebraid/top_level/trace_kernels.h"
#include "rebraid/top_level/two_level_builder.h"

namespace rebraid {

InstancedAccel::InstancedAccel(const Scene& scene, std::vector<ObjectBvh> object_bvhs,
                               TopLevelBvh top, const AccelStats& build_info)
    : object_bvhs_(std::move(object_bvhs)),
      top_(std::move(top)),
      build_info_(build_info),
      simd_level_(default_simd_level()),
      kernels_(&trace_kernels(simd_level_)) {
    instance_mesh_.reserve(scene.instances.size());
    object_to_world_.reserve(scene.instances.size());
    instance_targets_.reserve(scene.instances.size());
    object_views_.assign(object_bvhs_.begin(), object_bvhs_.end());
    // Distinct transforms by their exact bits: equal bits map every ray to equal bits. Ids
    // in order of first use, so they do not depend on the table's order. A hash table: a
    // million instances took a second in an ordered map.
    using TransformBits = std::array<std::uint32_t, 12>;
    const auto hash_bits = [](const TransformBits& bits) {
        std::uint64_t hash = 0xcbf29ce484222325ull;  // FNV-1a over the words
        for (const std::uint32_t word : bits) hash = (hash ^ word) * 0x100000001b3ull;
        return std::size_t(hash);
    };
    std::unordered_map<TransformBits, std::uint32_t, decltype(hash_bits)> space_of_bits(
        scene.instances.size(), hash_bits);
    const auto object_space_id = [&](const AffineTransform& to_object) {
        TransformBits bits;
        static_assert(sizeof(AffineTransform) == sizeof(bits));
        std::memcpy(bits.data(), &to_object, sizeof(bits));
        return space_of_bits.try_emplace(bits, std::uint32_t(space_of_bits.size() + 1))
            .first->second;
    };
    for (const Instance& instance : scene.instances) {
        if (instance.mesh_id >= object_bvhs_.size())
            throw Error("InstancedAccel: instance of mesh " + std::to_string(instance.mesh_id) +
                        " with " + std::to_string(object_bvhs_.size()) + " object BVHs");
        instance_mesh_.push_back(instance.mesh_id);
        object_to_world_.push_back(instance.object_to_world);
        InstanceTarget target;
        target.mesh = instance.mesh_id;
        if (instance.object_to_world != AffineTransform::identity()) {
            target.to_object = instance.object_to_world.inverse();
            target.space = object_space_id(target.to_object);
        }
        instance_targets_.push_back(target);
    }
    build_info_.triangles = scene.instanced_triangle_count();
    build_info_.instances = scene.instances.size();
    build_info_.meshes = scene.meshes.size();
}

Hit InstancedAccel::intersect_counted(const Ray& ray, TraversalCounters* counters) const {
    return kernels_->instanced_intersect(*this, ray, counters);
}

LocatedHit InstancedAccel::intersect_located(const Ray& ray) const {
    return kernels_->instanced_intersect_located(*this, ray);
}

bool InstancedAccel::occluded(const Ray& ray) const {
    return kernels_->instanced_occluded(*this, ray);
}

void InstancedAccel::set_simd_level(SimdLevel level) {
    kernels_ = &trace_kernels(level);
    simd_level_ = level;
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
    memory += object_to_world_.size() * sizeof(AffineTransform) +
              instance_targets_.size() * sizeof(InstanceTarget) +
              object_views_.size() * sizeof(ObjectBvhView);
    stats.nodes = nodes;
    stats.leaves = leaves;
    stats.memory_bytes = memory;
    stats.structure_hash = hash.value();
    stats.kernels = std::string(simd_level_name(simd_level_));
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
