#include "rebraid/top_level/world_tree.h"

#include <tbb/parallel_for.h>

#include <cstdint>
#include <vector>

#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/spatial_split_bvh_builder.h"
#include "rebraid/top_level/flattened_instances.h"

namespace rebraid {

bool wants_world_tree(const Scene& scene, const TopLevelMergeSettings& settings) {
    if (!settings.world_tree || scene.instances.size() < 2 ||
        scene.instances.size() > settings.world_tree_max_instances)
        return false;
    const std::uint64_t instanced = scene.instanced_triangle_count();
    if (instanced == 0 || instanced > settings.world_tree_max_triangles) return false;
    // The references the build may make must stay within what a leaf reference can name.
    const double references =
        double(instanced) * (1.0 + double(settings.world_tree_build.spatial_split_budget));
    return references <= double(NodeRef::kMaxFirst) &&
           double(instanced) <=
               double(settings.world_tree_triangle_budget) * double(scene.mesh_triangle_count());
}

MergedTopLevel build_world_tree(const Scene& scene, std::span<const InstanceTarget> targets,
                                const BuildSettings& settings) {
    MergedTopLevel tree;
    const FlattenedInstances flat = flatten_instances(scene, true);
    if (flat.world.triangles.empty()) return tree;
    BuildSettings build = settings;
    build.pre_arranged_leaves = true;  // the merged kernels read rows
    SpatialSplitBvh built = build_spatial_split_bvh(flat.world, build, flat.instance);
    if (built.tree.root.is_leaf()) return tree;
    // Nodes and boxes from the world-space build; corners from the object-space mesh of the
    // same numbering. Its prim_ids are positions in the flattened numbering until below.
    ObjectBvh leaves =
        make_object_bvh(flat.object, std::move(built.tree), std::move(built.leaf_prims), true);

    // One source per instance with leaves, numbered in node and slot order; each leaf slot's
    // hint word names its source (the kernels find a leaf's rows from its reference alone).
    std::vector<std::uint32_t> source_of_instance(scene.instances.size(), ~0u);
    for (WideNode& node : leaves.nodes) {
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef child = node.children[slot];
            if (!child.is_leaf() || child.is_empty()) continue;
            const InstanceId instance = flat.instance[leaves.prim_ids[child.first_prim()]];
            std::uint32_t& source = source_of_instance[instance];
            if (source == ~0u) {
                source = std::uint32_t(tree.sources.size());
                const InstanceTarget& target = targets[instance];
                tree.sources.push_back({.leaf_rows = leaves.leaf_rows.data() + kLeafRowPadding,
                                        .triangles = leaves.triangles.data(),
                                        .prim_ids = leaves.prim_ids.data(),
                                        .instance = instance,
                                        .target = &target,
                                        .space = target.space});
            }
            node.leaf_row_hints[slot] = MergedTopLevel::kSourceWordFlag | source;
        }
    }
    // A hit's primID, and the rows' id row, are the mesh's.
    tbb::parallel_for(std::size_t(0), leaves.prim_ids.size(),
                      [&](std::size_t i) { leaves.prim_ids[i] = flat.prim[leaves.prim_ids[i]]; });
    rewrite_leaf_row_ids(leaves.nodes, leaves.root, leaves.prim_ids, leaves.leaf_rows);
    tree.nodes = std::move(leaves.nodes);
    tree.root = leaves.root;
    tree.first_object_node = 0;
    tree.every_source_has_rows = true;
    tree.is_world_tree = true;
    tree.enters_items_out_of_line = false;  // no items to enter
    tree.rows_prefetch_from = NodeRef::kEmptyBits;
    tree.world_tree_leaves = std::move(leaves);
    return tree;
}

}  // namespace rebraid
