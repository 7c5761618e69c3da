#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <tbb/parallel_for.h>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/transform.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// Inner nodes and leaf references reachable from a root.
struct TreeCounts {
    std::uint64_t inner_nodes = 0;
    std::uint64_t leaves = 0;
};

TreeCounts count_tree(std::span<const WideNode> nodes, NodeRef root);

/// Half the surface area of `box` mapped by `object_to_world`: a parallelepiped, exactly the
/// region a ray tested against `box` in object space must cross. For convex regions the
/// chance that a random ray crossing one also crosses another inside it is the ratio of their
/// surface areas, so this is the area the SAH of an instanced object node needs.
double mapped_box_half_area(const BBox3f& box, const AffineTransform& object_to_world);

/// Unnormalised SAH cost of the object subtree at `ref`, entered when a ray hits `world_box`
/// (the world-space box a top level or the flat BVH tests before entering it): that box's
/// half area for the node itself, then for every deeper node the half area of its object box
/// mapped to world space (mapped_box_half_area), leaves weighted by their triangle count.
double object_subtree_cost(const ObjectBvh& bvh, NodeRef ref, const BBox3f& world_box,
                           const AffineTransform& object_to_world);

/// Unnormalised SAH cost of a world-space tree over `nodes` from `root`, entered when a ray
/// hits `root_box`, leaves weighted by their triangle count: a world tree's (world_tree.h).
double world_tree_cost(std::span<const WideNode> nodes, NodeRef root, const BBox3f& root_box);

/// SAH of a flat (world-space) BVH: object_subtree_cost of its root over its root area.
double object_bvh_sah(const ObjectBvh& bvh);

/// Sum of the half areas of the top level's inner nodes (each from its parent's stored box,
/// the root's from top.bounds), in depth-first order.
double top_inner_cost(const TopLevelBvh& top);

/// The world box of instance `instance_id`'s triangles: its object BVH's box for an identity
/// transform, else the box of its transformed vertices (vertex_world_bounds, exact).
BBox3f instance_world_bounds(InstanceId instance_id, std::span<const ObjectBvh> object_bvhs,
                             std::span<const std::uint32_t> instance_mesh,
                             std::span<const AffineTransform> object_to_world);

/// Half area of the union of `box_of(id)` over the instance ids `top`'s items reach (ids below
/// `instance_count`), `box_of` called once per such instance, in parallel: a union of boxes
/// does not depend on the order, so the result is the same on any thread count.
template <class BoxOf>
double reached_instances_half_area(const TopLevelBvh& top, std::size_t instance_count,
                                   BoxOf&& box_of) {
    std::vector<char> is_reached(instance_count, 0);
    for (const TopLevelItem& item : top.items) is_reached[item.instance_id] = 1;
    std::vector<BBox3f> boxes(instance_count);
    tbb::parallel_for(std::size_t(0), instance_count, [&](std::size_t i) {
        if (is_reached[i]) boxes[i] = box_of(InstanceId(i));
    });
    BBox3f scene;
    for (const BBox3f& box : boxes) scene.extend(box);
    return scene.half_area();
}

/// Half area of the union of instance_world_bounds() over the instances `top`'s items reach:
/// the box of the scene's world-space triangles, which is the root box of a flat BVH over
/// them. Every structure's SAH is normalised by it (docs/design.md, "SAH"), so that a top level
/// whose root box is larger than the scene (transformed boxes of rotated instances) is not given a
/// smaller SAH for it.
double instanced_scene_half_area(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
                                 std::span<const std::uint32_t> instance_mesh,
                                 std::span<const AffineTransform> object_to_world);

/// SAH of a two-level structure (docs/design.md, "SAH"): the top-level inner nodes' half areas
/// plus, for each item, the cost of its object subtree in world space, over the half area of the
/// scene's box (instanced_scene_half_area). `instance_mesh` and `object_to_world` are indexed
/// by instance id.
double top_level_sah(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
                     std::span<const std::uint32_t> instance_mesh,
                     std::span<const AffineTransform> object_to_world);

}  // namespace rebraid
