#include "rebraid/top_level/world_tree.h"

#include <tbb/parallel_for.h>

#include <cstdint>
#include <vector>

#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/spatial_split_bvh_builder.h"

namespace rebraid {
namespace {

/// Every instance's triangles, numbered alike in two meshes: `world` with the corners placed
/// by the instances (what the tree is built over) and `object` with their object-space
/// corners (what its leaves keep); per triangle its instance and its primID in its mesh.
struct FlattenedInstances {
    Mesh world, object;
    std::vector<std::uint32_t> instance;
    std::vector<PrimId> prim;
};

FlattenedInstances flatten_instances(const Scene& scene) {
    const std::size_t count = scene.instances.size();
    std::vector<std::uint64_t> vertex_offset(count + 1, 0), triangle_offset(count + 1, 0);
    for (std::size_t i = 0; i < count; ++i) {
        const Mesh& mesh = scene.meshes[scene.instances[i].mesh_id];
        vertex_offset[i + 1] = vertex_offset[i] + mesh.positions.size();
        triangle_offset[i + 1] = triangle_offset[i] + mesh.triangles.size();
    }
    FlattenedInstances out;
    out.world.name = "world tree";
    out.world.positions.resize(vertex_offset.back());
    out.object.positions.resize(vertex_offset.back());
    out.world.triangles.resize(triangle_offset.back());
    out.instance.resize(triangle_offset.back());
    out.prim.resize(triangle_offset.back());
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
        const Instance& instance = scene.instances[i];
        const Mesh& mesh = scene.meshes[instance.mesh_id];
        const auto base = std::uint32_t(vertex_offset[i]);
        for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
            out.object.positions[base + v] = mesh.positions[v];
            out.world.positions[base + v] =
                instance.object_to_world.transform_point(mesh.positions[v]);
        }
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const std::size_t at = triangle_offset[i] + t;
            const Triangle& triangle = mesh.triangles[t];
            out.world.triangles[at] = {base + triangle[0], base + triangle[1], base + triangle[2]};
            out.instance[at] = std::uint32_t(i);
            out.prim[at] = PrimId(t);
        }
    });
    out.object.triangles = out.world.triangles;
    return out;
}

}  // namespace

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
    FlattenedInstances flat = flatten_instances(scene);
    if (flat.world.triangles.empty()) return tree;
    BuildSettings build = settings;
    build.pre_arranged_leaves = true;  // the merged kernels read rows
    SpatialSplitBvh built = build_spatial_split_bvh(flat.world, build, flat.instance);
    if (built.tree.root.is_leaf()) return tree;
    // Nodes and boxes from the world-space build; corners from the object-space mesh of the
    // same numbering.
    const std::vector<PrimId> flat_prims = built.leaf_prims;
    ObjectBvh leaves =
        make_object_bvh(flat.object, std::move(built.tree), std::move(built.leaf_prims), true);
    // The rows' ids and a hit's primID are the mesh's.
    tbb::parallel_for(std::size_t(0), leaves.prim_ids.size(),
                      [&](std::size_t i) { leaves.prim_ids[i] = flat.prim[flat_prims[i]]; });
    leaves.refresh_leaf_rows();

    // One source per instance with leaves, numbered in node and slot order; each leaf slot's
    // hint word names its source (the kernels find a leaf's rows from its reference alone).
    std::vector<std::uint32_t> source_of_instance(scene.instances.size(), ~0u);
    for (WideNode& node : leaves.nodes) {
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef child = node.children[slot];
            if (!child.is_leaf() || child.is_empty()) continue;
            const std::uint32_t instance = flat.instance[flat_prims[child.first_prim()]];
            std::uint32_t& source = source_of_instance[instance];
            if (source == ~0u) {
                source = std::uint32_t(tree.sources.size());
                const InstanceTarget& target = targets[instance];
                tree.sources.push_back({.leaf_rows = leaves.leaf_rows.data() + kLeafRowPadding,
                                        .triangles = leaves.triangles.data(),
                                        .prim_ids = leaves.prim_ids.data(),
                                        .instance = InstanceId(instance),
                                        .target = &target,
                                        .space = target.space});
            }
            node.leaf_row_hints[slot] = MergedTopLevel::kSourceWordFlag | source;
        }
    }
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
