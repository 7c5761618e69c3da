#pragma once

#include <span>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/core/scene.h"
#include "rebraid/top_level/instance_target.h"
#include "rebraid/top_level/merged_top_level.h"

namespace rebraid {

/// A world tree: one BVH over the triangles of every instance of `scene`, built in world
/// space as the flat BVH is (spatial splits as `settings` allow, cutting across instances
/// where their parts overlap, which neither an object BVH nor re-braiding's BRefs can), whose
/// leaves each hold triangles of one instance, kept in that instance's object space: a leaf
/// is tested with the ray mapped into its instance (`targets[instance]`, read when tracing,
/// so maps set later count), as the leaves of merged placed instances are, so hits have the
/// bits entering the instance gives them. The result is a MergedTopLevel of no items, one
/// source per instance that has leaves (in the order of their first leaf in the nodes), whose
/// leaf slots may name different sources (`is_world_tree`), all pointing into the leaves'
/// arrays it owns
/// (`world_tree_leaves`). Empty when the scene has no triangles or the tree's root is a leaf.
/// Deterministic: the builder's tree depends on the input only.
MergedTopLevel build_world_tree(const Scene& scene, std::span<const InstanceTarget> targets,
                                const BuildSettings& settings);

/// Whether TopLevelMergeSettings::world_tree asks for a world tree of `scene`: 2 to
/// world_tree_max_instances instances, at most world_tree_max_triangles instanced triangles,
/// and those at most world_tree_triangle_budget times the meshes' triangles.
bool wants_world_tree(const Scene& scene, const TopLevelMergeSettings& settings);

}  // namespace rebraid
