#include "rebraid/top_level/two_level_builder.h"

#include <string>

#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"

namespace rebraid {

TopLevelBvh build_top_level_over_items(std::vector<TopLevelItem> items,
                                       std::vector<BBox3f> item_bounds,
                                       std::span<const std::uint32_t> item_prim_counts,
                                       const BuildSettings& settings) {
    std::vector<BuildPrim> prims(items.size());
    for (std::size_t i = 0; i < items.size(); ++i)
        prims[i] = {item_bounds[i], std::uint32_t(i), item_prim_counts[i]};
    WideBvh tree = build_wide_bvh(prims, settings);
    // Store items in leaf order so a leaf's items are contiguous.
    TopLevelBvh top;
    top.nodes = std::move(tree.nodes);
    top.root = tree.root;
    top.bounds = tree.bounds;
    top.items.resize(prims.size());
    top.item_bounds.resize(prims.size());
    for (std::size_t i = 0; i < prims.size(); ++i) {
        top.items[i] = items[prims[i].id];
        top.item_bounds[i] = item_bounds[prims[i].id];
    }
    return top;
}

TopLevelBvh build_two_level(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                            const BuildSettings& settings) {
    const BuildTimer timer;
    if (object_bvhs.size() != scene.meshes.size())
        throw Error("build_two_level: " + std::to_string(object_bvhs.size()) + " object BVHs for " +
                    std::to_string(scene.meshes.size()) + " meshes");
    std::vector<TopLevelItem> items;
    std::vector<BBox3f> bounds;
    std::vector<std::uint32_t> prim_counts;
    items.reserve(scene.instances.size());
    bounds.reserve(scene.instances.size());
    prim_counts.reserve(scene.instances.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& instance = scene.instances[i];
        const ObjectBvh& bvh = object_bvhs[instance.mesh_id];
        if (bvh.root.is_empty()) continue;
        items.push_back({InstanceId(i), bvh.root});
        bounds.push_back(instance.object_to_world.transform_bbox_conservative(bvh.bounds));
        prim_counts.push_back(bvh.prim_count());
    }
    TopLevelBvh top =
        build_top_level_over_items(std::move(items), std::move(bounds), prim_counts, settings);
    top.build_ms = timer.elapsed_ms();
    return top;
}

}  // namespace rebraid
