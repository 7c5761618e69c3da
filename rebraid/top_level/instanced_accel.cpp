#include "rebraid/top_level/instanced_accel.h"

#include <array>
#include <cstring>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"
#include "rebraid/core/huge_pages.h"
#include "rebraid/core/structure_hash.h"
#include "rebraid/top_level/bvh_stats.h"
#include "rebraid/top_level/trace_kernels.h"
#include "rebraid/top_level/two_level_builder.h"
#include "rebraid/top_level/world_tree.h"

namespace rebraid {
namespace {

bool same_bits(const AffineTransform& a, const AffineTransform& b) {
    return std::memcmp(&a, &b, sizeof(AffineTransform)) == 0;
}

/// Instances placed by transforms of equal bits share one space, the lowest `space` among
/// them (each mapped instance's own number on entry): equal bits map every ray to equal bits,
/// so a ray mapped once serves all of them (a file's root rotation often places every mesh).
/// Sorted by a hash of the bits, then compared exactly within equal hashes: parallel, and
/// the answer depends on the instances only.
void share_object_spaces(std::vector<InstanceTarget>& targets) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;  // (hash, instance)
    reserve_on_huge_pages(keyed, targets.size());
    for (std::size_t i = 0; i < targets.size(); ++i)
        if (targets[i].space != InstanceTarget::kWorldSpace) keyed.push_back({0, std::uint32_t(i)});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keyed.size()), [&](const auto& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            std::array<std::uint32_t, 12> bits;
            static_assert(sizeof(AffineTransform) == sizeof(bits));
            std::memcpy(bits.data(), &targets[keyed[k].second].to_object, sizeof(bits));
            std::uint64_t hash = 0xcbf29ce484222325ull;  // FNV-1a over the words
            for (const std::uint32_t word : bits) hash = (hash ^ word) * 0x100000001b3ull;
            keyed[k].first = hash;
        }
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    // Runs of one hash: almost always one transform, in instance order, so the first of each
    // distinct transform in a run is its lowest instance.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keyed.size()), [&](const auto& range) {
        std::vector<std::uint32_t> firsts;
        for (std::size_t begin = range.begin(); begin != range.end(); ++begin) {
            if (begin > 0 && keyed[begin - 1].first == keyed[begin].first) continue;
            firsts.clear();
            for (std::size_t k = begin; k < keyed.size() && keyed[k].first == keyed[begin].first;
                 ++k) {
                InstanceTarget& target = targets[keyed[k].second];
                bool is_shared = false;
                for (const std::uint32_t first : firsts)
                    if (same_bits(targets[first].to_object, target.to_object)) {
                        target.space = targets[first].space;
                        is_shared = true;
                        break;
                    }
                if (!is_shared) firsts.push_back(keyed[k].second);
            }
        }
    });
}

}  // namespace

InstancedAccel::InstancedAccel(const Scene& scene, std::vector<ObjectBvh> object_bvhs,
                               TopLevelBvh top, const AccelStats& build_info,
                               const TopLevelMergeSettings& merge)
    : object_bvhs_(std::move(object_bvhs)),
      top_(std::move(top)),
      build_info_(build_info),
      simd_level_(default_simd_level()) {
    // The instance records count as top-level build time: a frame that moves instances makes
    // them again (a million instances: hundreds of milliseconds).
    const BuildTimer timer;
    const std::size_t count = scene.instances.size();
    for (const Instance& instance : scene.instances)
        if (instance.mesh_id >= object_bvhs_.size())
            throw Error("InstancedAccel: instance of mesh " + std::to_string(instance.mesh_id) +
                        " with " + std::to_string(object_bvhs_.size()) + " object BVHs");
    object_views_.assign(object_bvhs_.begin(), object_bvhs_.end());
    // Whether rows are asked for ahead is the structure's choice: what the caches hold is all
    // its object BVHs' rows, not one's.
    std::uint64_t row_floats = 0;
    for (const ObjectBvh& bvh : object_bvhs_) row_floats += bvh.leaf_rows.size();
    for (ObjectBvhView& view : object_views_)
        view.prefetches_rows = prefetches_leaf_rows(row_floats);
    // On huge pages when large: fewer first-touch faults, and rays reach the records of
    // instances all over the scene.
    reserve_on_huge_pages(instance_mesh_, count);
    reserve_on_huge_pages(object_to_world_, count);
    reserve_on_huge_pages(instance_targets_, count);
    instance_mesh_.resize(count);
    object_to_world_.resize(count);
    instance_targets_.resize(count);
    // The records in parallel: a million instances, each an inverse and a 64-byte record.
    // `space` is first the instance's own number; below, instances placed alike take the
    // lowest number among them.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const Instance& instance = scene.instances[i];
            instance_mesh_[i] = instance.mesh_id;
            object_to_world_[i] = instance.object_to_world;
            InstanceTarget& target = instance_targets_[i];
            target.mesh = instance.mesh_id;
            if (instance.object_to_world != AffineTransform::identity()) {
                target.to_object = instance.object_to_world.inverse();
                target.space = std::uint32_t(i + 1);
            }
        }
    });
    share_object_spaces(instance_targets_);
    // Part of the top level's build time too: it is made again with every top level.
    if (wants_world_tree(scene, merge))
        merged_ = build_world_tree(scene, instance_targets_, merge.world_tree_build);
    if (merged_.empty() && (merge.world_space || merge.placed_instances)) {
        std::uint64_t object_nodes = 0;
        for (const ObjectBvh& bvh : object_bvhs_) object_nodes += bvh.nodes.size();
        merged_ = merge_top_level_items(top_, instance_targets_, object_views_, object_to_world_,
                                        object_nodes, merge);
    }
    use_kernels(simd_level_, triangle_test_);
    refresh_root_box();
    const double records_ms = timer.elapsed_ms();
    build_info_.build_ms += records_ms;
    build_info_.top_build_ms = build_info_.top_build_ms.value_or(0.0) + records_ms;
    build_info_.triangles = scene.instanced_triangle_count();
    build_info_.instances = scene.instances.size();
    // The scene's meshes: copies a build made of them (AccelStats::mesh_copies) are its own.
    build_info_.meshes = scene.meshes.size() - build_info_.mesh_copies.value_or(0);
}

Hit InstancedAccel::intersect_counted(const Ray& ray, TraversalCounters* counters) const {
    return intersect_(*this, ray, counters);
}

bool InstancedAccel::occluded(const Ray& ray) const {
    return occluded_(*this, ray);
}

void InstancedAccel::use_kernels(SimdLevel level, TriangleTest test) {
    const TraceKernels& kernels = trace_kernels(level, test);
    // A top level of one item: no top-level traversal to run (TraceKernels::sole_item_*).
    if (has_sole_item()) {
        refresh_sole_item();
        intersect_ = kernels.sole_item_intersect;
        occluded_ = kernels.sole_item_occluded;
        intersect_located_ = kernels.sole_item_intersect_located;
    } else if (!merged_.empty() && merged_.is_world_tree) {
        intersect_ = kernels.world_tree_intersect;
        occluded_ = kernels.world_tree_occluded;
        intersect_located_ = kernels.world_tree_intersect_located;
    } else if (!merged_.empty() && merged_.enters_items_out_of_line) {
        intersect_ = kernels.merged_rare_items_intersect;
        occluded_ = kernels.merged_rare_items_occluded;
        intersect_located_ = kernels.merged_rare_items_intersect_located;
    } else if (!merged_.empty()) {
        intersect_ = kernels.merged_intersect;
        occluded_ = kernels.merged_occluded;
        intersect_located_ = kernels.merged_intersect_located;
    } else {
        intersect_ = kernels.instanced_intersect;
        occluded_ = kernels.instanced_occluded;
        intersect_located_ = kernels.instanced_intersect_located;
    }
}

bool InstancedAccel::has_sole_item() const {
    return top_.root.is_leaf() && top_.root.prim_count() == 1;
}

void InstancedAccel::refresh_sole_item() {
    if (!has_sole_item()) return;
    const TopLevelItem& item = top_.items[top_.root.first_prim()];
    const InstanceTarget& target = instance_targets_[item.instance_id];
    sole_item_.target = target;
    sole_item_.bvh = object_views_[target.mesh];
    sole_item_.node = item.object_node;
    sole_item_.instance = item.instance_id;
}

void InstancedAccel::refresh_root_box() {
    if (!culls_root_box_) {
        root_box_ = RootBox{};  // all of space: no ray starts outside it
    } else if (has_sole_item()) {
        // No root node of its own: the item's node is the root, in world space only where
        // its instance is placed by the identity.
        const SoleItem& item = sole_item_;
        root_box_ = item.target.space == InstanceTarget::kWorldSpace
                        ? root_box_of(object_bvhs_[item.target.mesh].nodes, item.node)
                        : RootBox{};
    } else {
        root_box_ = merged_.empty() ? root_box_of(top_.nodes, top_.root)
                                    : root_box_of(merged_.nodes, merged_.root);
    }
}

void InstancedAccel::set_culls_root_box(bool culls) {
    culls_root_box_ = culls;
    refresh_root_box();
}

void InstancedAccel::set_simd_level(SimdLevel level) {
    use_kernels(level, triangle_test_);
    simd_level_ = level;
}

void InstancedAccel::set_world_to_object(std::span<const AffineTransform> world_to_object) {
    if (world_to_object.size() != instance_targets_.size())
        throw Error(
            "InstancedAccel::set_world_to_object: " + std::to_string(world_to_object.size()) +
            " maps for " + std::to_string(instance_targets_.size()) + " instances");
    // Instances placed alike share a space (share_object_spaces); maps computed from equal
    // transforms are equal, so the spaces stay right.
    for (std::size_t i = 0; i < instance_targets_.size(); ++i)
        if (instance_targets_[i].space != InstanceTarget::kWorldSpace)
            instance_targets_[i].to_object = world_to_object[i];
    // The root box stays: it depends on the structure and the cull setting only.
    refresh_sole_item();
}

void InstancedAccel::set_triangle_test(TriangleTest test) {
    use_kernels(simd_level_, test);
    triangle_test_ = test;
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
    if (!merged_.world_tree_leaves.prim_ids.empty()) {
        // A world tree is built from the scene, not from the structures above.
        hash.add<WideNode>(merged_.nodes);
        hash.add_value(merged_.root);
        hash.add<PrimId>(merged_.world_tree_leaves.prim_ids);
    }
    memory += object_to_world_.size() * sizeof(AffineTransform) +
              instance_targets_.size() * sizeof(InstanceTarget) +
              object_views_.size() * sizeof(ObjectBvhView) + merged_.memory_bytes();
    stats.nodes = nodes;
    stats.leaves = leaves;
    if (merged_.is_world_tree) {
        // What the queries traverse is the world tree: its cost over the same scene area as
        // every structure's, and its nodes and leaves.
        const double scene_area =
            instanced_scene_half_area(top_, object_bvhs_, instance_mesh_, object_to_world_);
        const double cost =
            world_tree_cost(merged_.nodes, merged_.root, merged_.world_tree_leaves.bounds);
        stats.sah = scene_area > 0.0 ? cost / scene_area : 0.0;
        const TreeCounts counts = count_tree(merged_.nodes, merged_.root);
        stats.nodes = counts.inner_nodes;
        stats.leaves = counts.leaves;
    }
    stats.memory_bytes = memory;
    stats.structure_hash = hash.value();
    stats.kernels = std::string(simd_level_name(simd_level_));
    stats.triangle_test = std::string(triangle_test_name(triangle_test_));
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
