#pragma once

#include <cstddef>
#include <cstdint>

#include "rebraid/bvh/wide_node.h"

namespace rebraid {

/// How a wide BVH's nodes are cut out of the binary tree of SAH splits.
enum class NodeCollapse {
    /// Fill each node by splitting its child of largest area until it has max_children
    /// children or every child is a leaf.
    greedy,
    /// Choose the nodes that minimise the sum of their areas (the SAH's node cost) under the
    /// limit of max_children children each (optimal_wide_tree_grower.h).
    optimal,
};

/// Parameters of the binned-SAH wide-BVH builder (object BVHs, the flat BVH and the top
/// levels). Defaults are the values the benchmarks in bench/RESULTS.md use.
struct BuildSettings {
    /// SAH bins per axis; more bins find better splits at a higher build cost.
    std::uint32_t bin_count = 32;
    /// Leaves hold at most this many primitives (1..16). 8 is one triangle group test
    /// (rebraid/bvh/triangle_group.h), so a full leaf costs one test.
    std::uint32_t max_leaf_size = 8;
    /// SAH cost of visiting a node, relative to `intersection_cost`.
    float traversal_cost = 1.0f;
    /// SAH cost of one primitive test. A triangle costs far less than a node visit: the group
    /// test handles 8 at once, and a leaf's triangles sit on one or two cache lines where a
    /// node takes four. 0.3 traced fastest of 1, 0.5, 0.3 and 0.2 on the shared scenes
    /// (docs/design.md, "Leaves"); top levels (max_leaf_size 1) never weigh it.
    float intersection_cost = 0.3f;
    /// Ranges with fewer primitives are binned and partitioned serially, larger ones in
    /// parallel blocks. The prim order within the tree (and, through ties and index splits,
    /// rarely its shape) depends on this value; nothing depends on the thread count.
    std::size_t parallel_threshold = 8192;
    /// Subtrees of at least this many primitives are built as their own TBB task; smaller
    /// ones by their parent's task. Lower than `parallel_threshold` because a task costs far
    /// less than a parallel loop, and many mid-sized subtrees keep every thread busy. Node
    /// numbering depends on this value, the tree's shape does not; neither depends on the
    /// thread count.
    std::size_t task_threshold = 1024;
    /// Ranges of fewer than bin_count * prims_per_bin primitives get one bin per this many
    /// primitives (at least 4 bins): small ranges spend most of their split search clearing
    /// and sweeping bins. 2 builds the shared scenes about 6% faster than 1 for an SAH
    /// within 0.02%; 4 costs up to 0.8% SAH.
    std::uint32_t prims_per_bin = 2;
    /// Fill wide nodes by also splitting children the binary SAH test would keep as leaves
    /// (any child of more than one prim, largest first). Off by default: with the SAH's
    /// leaves of several triangles, splitting them only to fill slots traced a little slower
    /// and built slower.
    bool fill_nodes = false;
    /// How nodes are cut out of the binary tree of splits. Optimal by default: on the shared
    /// scenes a diffuse ray visits 4 to 6 % fewer nodes than with greedy, for the same leaves
    /// (docs/design.md, "Leaves"). fill_nodes needs greedy (the optimal cut keeps the SAH's
    /// leaves).
    NodeCollapse collapse = NodeCollapse::optimal;
    /// Children per node, 2..kBvhWidth. Nodes keep kBvhWidth slots and the traversal tests
    /// all of them at once, so fewer children only make the tree deeper: a setting for
    /// measuring what the 8-wide layout buys (bench/bench_traversal.cpp's max_children).
    std::uint32_t max_children = kBvhWidth;
    /// Keep each leaf's corners also pre-arranged for the SIMD triangle test (leaf_rows.h):
    /// 40 more bytes per triangle (the corners and the primID), for no transpose per test and
    /// no id lookup per hit (docs/design.md, "Leaves").
    /// Without them the kernels gather corners from the per-triangle copies.
    bool pre_arranged_leaves = true;
    /// Object BVHs: room for this many more triangle references, as a fraction of the
    /// triangles, that spatial splits may spend (spatial_split_bvh_builder.h); 0 builds with
    /// object splits only. Top levels ignore it.
    float spatial_split_budget = 0.0f;

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// Room for spatial splits in object BVHs built once (BuildSettings::spatial_split_budget):
/// 20 % more references. On the shared and generated scenes the own flat BVH traced up to 16 %
/// more rays per second than without, the re-braided structure between 4 % fewer and 10 % more
/// (two_cylinder_engine), for 1-18 % more memory and builds 1.5-4.6 times as long
/// (docs/design.md, "Spatial splits").
inline constexpr float kStaticSpatialSplitBudget = 0.2f;

/// The settings of object BVHs built once for geometry that stays as it is (`flat`, the
/// object BVHs of the two-level and re-braided structures, the drop-in's, a dynamic scene's
/// static meshes): the defaults plus spatial splits. Meshes that deform keep the plain
/// defaults: their updates refit, rotate and rebuild often.
inline BuildSettings static_object_build_settings() {
    BuildSettings settings;
    settings.spatial_split_budget = kStaticSpatialSplitBudget;
    return settings;
}

}  // namespace rebraid
