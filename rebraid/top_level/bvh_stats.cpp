#include "rebraid/top_level/bvh_stats.h"

#include <tbb/parallel_for.h>

#include <vector>

#include "rebraid/bvh/vertex_world_bounds.h"

namespace rebraid {
namespace {

/// Sum of half areas of the top-level inner nodes below `ref` (whose box is `box`).
double inner_cost_below(const TopLevelBvh& top, NodeRef ref, const BBox3f& box) {
    if (!ref.is_inner()) return 0.0;
    const WideNode& node = top.nodes[ref.node_id()];
    double cost = box.half_area();
    for (int i = 0; i < kBvhWidth && !node.children[i].is_empty(); ++i)
        cost += inner_cost_below(top, node.children[i], node.child_bounds(i));
    return cost;
}

}  // namespace

double top_inner_cost(const TopLevelBvh& top) {
    return inner_cost_below(top, top.root, top.bounds);
}

BBox3f instance_world_bounds(InstanceId instance_id, std::span<const ObjectBvh> object_bvhs,
                             std::span<const std::uint32_t> instance_mesh,
                             std::span<const AffineTransform> object_to_world) {
    const ObjectBvh& bvh = object_bvhs[instance_mesh[instance_id]];
    const AffineTransform& to_world = object_to_world[instance_id];
    if (to_world == AffineTransform::identity()) return bvh.bounds;
    return vertex_world_bounds(bvh, bvh.root, bvh.bounds, to_world, 0.0f);
}

double instanced_scene_half_area(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
                                 std::span<const std::uint32_t> instance_mesh,
                                 std::span<const AffineTransform> object_to_world) {
    return reached_instances_half_area(top, object_to_world.size(), [&](InstanceId id) {
        return instance_world_bounds(id, object_bvhs, instance_mesh, object_to_world);
    });
}

TreeCounts count_tree(std::span<const WideNode> nodes, NodeRef root) {
    TreeCounts counts;
    if (root.is_empty()) return counts;
    if (root.is_leaf()) return {0, 1};
    std::vector<NodeRef> stack{root};
    while (!stack.empty()) {
        const NodeRef ref = stack.back();
        stack.pop_back();
        ++counts.inner_nodes;
        for (NodeRef child : nodes[ref.node_id()].children) {
            if (child.is_leaf()) ++counts.leaves;
            if (child.is_inner()) stack.push_back(child);
        }
    }
    return counts;
}

double mapped_box_half_area(const BBox3f& box, const AffineTransform& object_to_world) {
    if (box.is_empty()) return 0.0;
    const Vec3f d = box.extent();
    const Vec3f a = object_to_world.col_x * d.x;
    const Vec3f b = object_to_world.col_y * d.y;
    const Vec3f c = object_to_world.col_z * d.z;
    return double(length(cross(a, b))) + length(cross(b, c)) + length(cross(c, a));
}

namespace {

/// Cost of the object subtree at `ref` given the half area of the region whose hit makes the
/// ray visit it (`entry_area`).
double object_subtree_cost_from(const WideNode* nodes, NodeRef ref, double entry_area,
                                const AffineTransform& object_to_world) {
    if (ref.is_empty()) return 0.0;
    if (ref.is_leaf()) return entry_area * ref.prim_count();
    const WideNode& node = nodes[ref.node_id()];
    double cost = entry_area;
    for (int i = 0; i < kBvhWidth && !node.children[i].is_empty(); ++i)
        cost += object_subtree_cost_from(
            nodes, node.children[i], mapped_box_half_area(node.child_bounds(i), object_to_world),
            object_to_world);
    return cost;
}

}  // namespace

double object_subtree_cost(const ObjectBvh& bvh, NodeRef ref, const BBox3f& world_box,
                           const AffineTransform& object_to_world) {
    return object_subtree_cost_from(bvh.nodes.data(), ref, world_box.half_area(), object_to_world);
}

double world_tree_cost(std::span<const WideNode> nodes, NodeRef root, const BBox3f& root_box) {
    return object_subtree_cost_from(nodes.data(), root, root_box.half_area(),
                                    AffineTransform::identity());
}

double object_bvh_sah(const ObjectBvh& bvh) {
    const double root_area = bvh.bounds.half_area();
    if (root_area <= 0.0) return 0.0;
    return object_subtree_cost(bvh, bvh.root, bvh.bounds, AffineTransform::identity()) / root_area;
}

double top_level_sah(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
                     std::span<const std::uint32_t> instance_mesh,
                     std::span<const AffineTransform> object_to_world) {
    const double scene_area =
        instanced_scene_half_area(top, object_bvhs, instance_mesh, object_to_world);
    if (scene_area <= 0.0) return 0.0;
    // Items in parallel; the partial costs are summed in item order so the total is
    // reproducible to the last bit.
    std::vector<double> item_costs(top.items.size());
    tbb::parallel_for(std::size_t(0), top.items.size(), [&](std::size_t i) {
        const TopLevelItem& item = top.items[i];
        item_costs[i] =
            object_subtree_cost(object_bvhs[instance_mesh[item.instance_id]], item.object_node,
                                top.item_bounds[i], object_to_world[item.instance_id]);
    });
    double cost = top_inner_cost(top);
    for (double c : item_costs) cost += c;
    return cost / scene_area;
}

}  // namespace rebraid
