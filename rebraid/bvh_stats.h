#pragma once

#include <cstdint>
#include <span>

#include "rebraid/object_bvh.h"
#include "rebraid/top_level_bvh.h"
#include "rebraid/transform.h"

namespace rebraid {

/// Inner nodes and leaf references reachable from a root.
struct TreeCounts {
    std::uint64_t inner_nodes = 0;
    std::uint64_t leaves = 0;
};

TreeCounts count_tree(std::span<const WideNode> nodes, NodeRef root);

/// Unnormalised SAH cost of the object subtree at `ref` whose world box is `world_box`:
/// the half area of every inner node (one per node visit) plus, for leaves, half area times
/// triangle count; boxes of deeper nodes are their object boxes mapped by `object_to_world`
/// (conservative AABBs, as traversal of a transformed instance sees them).
double object_subtree_cost(const ObjectBvh& bvh, NodeRef ref, const BBox3f& world_box,
                           const AffineTransform& object_to_world);

/// SAH of a flat (world-space) BVH: object_subtree_cost of its root over its root area.
double object_bvh_sah(const ObjectBvh& bvh);

/// SAH of a two-level structure (README "SAH"): the top-level inner nodes' half areas plus,
/// for each item, the cost of its object subtree in world space, over the root half area.
/// `instance_mesh` and `object_to_world` are indexed by instance id.
double top_level_sah(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
                     std::span<const std::uint32_t> instance_mesh,
                     std::span<const AffineTransform> object_to_world);

}  // namespace rebraid
