#pragma once

#include <span>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// Settings of the plain top-level builder: one top-level leaf per instance, nodes filled
/// greedily. The optimal collapse lowers a top level's node cost too, but its nodes then mix
/// large subtrees with single instances, and the closest-hit order by entry distance enters
/// the large ones too early: the re-braided top of two_cylinder_engine (its 67 instances,
/// none opened) built so took 3.6 % more instructions per primary ray (docs/design.md,
/// "Leaves").
inline BuildSettings default_top_level_settings() {
    BuildSettings settings;
    settings.max_leaf_size = 1;
    settings.collapse = NodeCollapse::greedy;
    return settings;
}

/// The plain two-level top: binned SAH over each instance's world bounds (its object root
/// box transformed, conservatively), each bin weighted by the instance's triangle count,
/// leaves referencing object roots. Instances of empty meshes are left out.
TopLevelBvh build_two_level(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                            const BuildSettings& settings = default_top_level_settings());

/// Builds a top-level BVH over `items` whose world bounds and prim counts are given (the
/// plain builder's emission). Items name object nodes or whole object leaves: the result's
/// has_partial_leaves is false.
TopLevelBvh build_top_level_over_items(std::vector<TopLevelItem> items,
                                       std::vector<BBox3f> item_bounds,
                                       std::span<const std::uint32_t> item_prim_counts,
                                       const BuildSettings& settings);

}  // namespace rebraid
