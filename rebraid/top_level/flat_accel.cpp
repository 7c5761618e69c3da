#include "rebraid/top_level/flat_accel.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/huge_pages.h"
#include "rebraid/core/structure_hash.h"
#include "rebraid/top_level/bvh_stats.h"
#include "rebraid/top_level/flattened_instances.h"
#include "rebraid/top_level/trace_kernels.h"

namespace rebraid {
namespace {

/// Renumbers the world triangles in the BVH's leaf order (bvh.prim_ids becomes the identity):
/// a hit's leaf position then names its instance and primID with one lookup instead of two
/// dependent ones, and the arrays are read in the order traversal touches them.
void renumber_in_leaf_order(ObjectBvh& bvh, std::vector<InstanceId>& triangle_instance,
                            std::vector<PrimId>& triangle_prim) {
    const std::size_t count = bvh.prim_ids.size();
    std::vector<InstanceId> instances;
    std::vector<PrimId> prims;
    reserve_on_huge_pages(instances, count);
    reserve_on_huge_pages(prims, count);
    instances.resize(count);
    prims.resize(count);
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
        const PrimId world_prim = bvh.prim_ids[i];
        instances[i] = triangle_instance[world_prim];
        prims[i] = triangle_prim[world_prim];
        bvh.prim_ids[i] = PrimId(i);
    });
    triangle_instance = std::move(instances);
    triangle_prim = std::move(prims);
}

}  // namespace

FlatAccel::FlatAccel(const Scene& scene, const BuildSettings& settings)
    : simd_level_(default_simd_level()), kernels_(&trace_kernels(simd_level_, triangle_test_)) {
    scene.validate();
    const BuildTimer timer;
    FlattenedInstances flat = flatten_instances(scene, false);
    triangle_instance_ = std::move(flat.instance);
    triangle_prim_ = std::move(flat.prim);
    bvh_ = build_object_bvh(flat.world, settings);
    renumber_in_leaf_order(bvh_, triangle_instance_, triangle_prim_);
    write_hit_ids(scene);
    root_box_ = root_box_of(bvh_.nodes, bvh_.root);
    build_info_.build_ms = timer.elapsed_ms();
    build_info_.triangles = scene.instanced_triangle_count();
    build_info_.instances = scene.instances.size();
    build_info_.meshes = scene.meshes.size();
}

void FlatAccel::write_hit_ids(const Scene& scene) {
    std::size_t max_triangles = 0;
    for (const Mesh& mesh : scene.meshes)
        max_triangles = std::max(max_triangles, mesh.triangles.size());
    hit_ids_ = FlatHitIds::for_scene(scene.instances.size(), max_triangles);
    if (bvh_.leaf_rows.empty()) return;
    // The id row names the triangle by its leaf position (the tables' index) where the pair
    // does not pack; the kernels read it only where it does.
    std::vector<std::uint32_t> words(triangle_prim_.size());
    tbb::parallel_for(std::size_t(0), words.size(), [&](std::size_t i) {
        words[i] = hit_ids_.packs ? hit_ids_.pack(triangle_instance_[i], triangle_prim_[i])
                                  : std::uint32_t(i);
    });
    rewrite_leaf_row_ids(bvh_.nodes, bvh_.root, words, bvh_.leaf_rows);
}

Hit FlatAccel::intersect_counted(const Ray& ray, TraversalCounters* counters) const {
    return kernels_->flat_intersect(*this, ray, counters);
}

bool FlatAccel::occluded(const Ray& ray) const {
    return kernels_->flat_occluded(*this, ray);
}

void FlatAccel::set_simd_level(SimdLevel level) {
    kernels_ = &trace_kernels(level, triangle_test_);
    simd_level_ = level;
}

void FlatAccel::set_triangle_test(TriangleTest test) {
    kernels_ = &trace_kernels(simd_level_, test);
    triangle_test_ = test;
}

AccelStats FlatAccel::stats() const {
    AccelStats stats = build_info_;
    stats.sah = object_bvh_sah(bvh_);
    const TreeCounts counts = count_tree(bvh_.nodes, bvh_.root);
    stats.nodes = counts.inner_nodes;
    stats.leaves = counts.leaves;
    stats.memory_bytes = bvh_.memory_bytes() + triangle_instance_.size() * sizeof(InstanceId) +
                         triangle_prim_.size() * sizeof(PrimId);
    StructureHash hash;
    hash.add<WideNode>(bvh_.nodes);
    hash.add_value(bvh_.root);
    hash.add<PrimId>(bvh_.prim_ids);
    hash.add<InstanceId>(triangle_instance_);
    hash.add<PrimId>(triangle_prim_);
    stats.structure_hash = hash.value();
    stats.kernels = std::string(simd_level_name(simd_level_));
    stats.triangle_test = std::string(triangle_test_name(triangle_test_));
    return stats;
}

}  // namespace rebraid
