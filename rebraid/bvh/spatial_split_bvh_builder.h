#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/wide_bvh.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// How the spatial split search went in one build.
struct SpatialSplitSearchCounts {
    /// Ranges of at least 4 references with room left for cuts.
    std::uint64_t candidates = 0;
    /// Ranges among them where a spatial split was searched: their object split's halves
    /// overlap, and the search had not come up empty four times in a row above them.
    std::uint64_t searches = 0;
    /// Searches that found a spatial split cheaper than the object split.
    std::uint64_t cheaper = 0;
    /// The most searches in a row on one way down that found none cheaper (at most 4).
    std::uint32_t longest_fruitless_run = 0;
};

/// A wide BVH whose leaves index `leaf_prims`: the triangles in leaf order, a triangle cut by
/// spatial splits listed once in each leaf that holds a part of it.
struct SpatialSplitBvh {
    WideBvh tree;
    std::vector<PrimId> leaf_prims;
    SpatialSplitSearchCounts search_counts;
};

/// The binned-SAH build of build_wide_bvh over the triangles of `mesh`, where each range also
/// weighs a spatial split (spatial_split.h) against the object split and takes the cheaper
/// (Stich et al. 2009). The references live in one array of the triangle count plus
/// `settings.spatial_split_budget` times as many more, divided into segments: a range owns its
/// references and the room after them, spends that room on the duplicates of its spatial
/// splits, and hands what is left to its two halves in proportion to their reference counts
/// (as the re-braiding paper's budgeted segments, §5.2), so the tree depends on the input and
/// the settings only, never on the threads. Below four searches in a row on the way down that
/// found no spatial split cheaper than the object split, ranges search no more (splits rarely
/// pay there). Nodes are cut from the binary tree by the optimal collapse. A budget of 0 leaves
/// no room: object splits only. `leaf_groups`, when not empty, gives each triangle a group,
/// and no leaf holds triangles of two groups (a range that mixes them is split further,
/// whatever the SAH says). Throws rebraid::Error unless settings.collapse ==
/// NodeCollapse::optimal (BuildSettings::validate), or when `leaf_groups` is neither empty nor
/// one per triangle.
SpatialSplitBvh build_spatial_split_bvh(const Mesh& mesh, const BuildSettings& settings,
                                        std::span<const std::uint32_t> leaf_groups = {});

}  // namespace rebraid
