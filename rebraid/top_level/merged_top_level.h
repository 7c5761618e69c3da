#pragma once

#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/transform.h"
#include "rebraid/core/triangle.h"
#include "rebraid/core/types.h"
#include "rebraid/top_level/instance_target.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// Where the triangles of one merged subtree's leaves are (its object BVH's arrays), and the
/// space its boxes and corners are in.
struct MergedLeafSource {
    const float* leaf_rows = nullptr;          ///< ObjectBvhView::leaf_rows
    const TriangleVerts* triangles = nullptr;  ///< ObjectBvhView::triangles
    const PrimId* prim_ids = nullptr;          ///< ObjectBvhView::prim_ids
    InstanceId instance = 0;
    /// The instance's target (its world-to-object map), and its space: kWorldSpace, or the
    /// space rays are mapped into (ObjectRayCache) before they test this subtree's triangles.
    const InstanceTarget* target = nullptr;
    std::uint32_t space = InstanceTarget::kWorldSpace;
};

/// Which items merge_top_level_items copies into the traced tree.
struct TopLevelMergeSettings {
    /// Items of instances placed by the identity (objects built in world space), where at
    /// least half of the top's items are in world space or the placed items merge too.
    bool world_space = true;
    /// Also items of placed instances: their copied nodes get world-space boxes (their
    /// triangles' corners mapped into the world, widened for the mapping's rounding as BRef
    /// boxes are), so the world ray tests them as the top level's own, and their triangles
    /// stay in object space, tested with the ray mapped as entering the item maps it (once
    /// per run of leaves in the same space): the same hits, with the same bits. One loop and
    /// one stack across both levels, nearest node first whatever its instance.
    bool placed_instances = false;
    /// Placed items are merged only while their copies add at most this many nodes per
    /// inner node of the scene's object BVHs (an instance's copy is its own: a mesh placed
    /// many times is copied as often).
    float placed_node_budget = 1.0f;
    /// The queries enter the items left in the tree out of line where their boxes' areas add
    /// up to at most this share of the root box's (the entries expected of a ray that crosses
    /// the scene; infinity: always, 0: only where no item is left), and in the traversal's
    /// loop elsewhere. Out of line, the loop keeps the world ray in registers and pays for
    /// each entry a call, a ray prepared again and its own registers saved:
    /// bench/tools/kernel_ab.py, out of line over in the loop (docs/design.md, "The rare parts
    /// of a merged query out of line"), primary / diffuse rays, brainstem (area share 0.11)
    /// 1.03 / 1.03, cg57_cruiser (0.25) 1.04 / 1.02, fzk_haus (1.58; 0.73 entries per diffuse
    /// ray) 0.94 / 0.96.
    float items_out_of_line_area_share = 0.5f;
    /// Instead of copying object subtrees, trace a world tree (world_tree.h): one BVH over every
    /// instance's triangles, built in world space with spatial splits that cut across
    /// instances, whose leaves each hold triangles of one instance, kept in object space and
    /// tested as the placed items' leaves are. Built only for scenes of 2 to
    /// `world_tree_max_instances` instances and at most `world_tree_max_triangles` instanced
    /// triangles, those at most `world_tree_triangle_budget` times their meshes' triangles
    /// (the tree holds a copy of every instanced triangle). It pays where few large instances
    /// overlap; where rays cross many instances, each leaf's own ray costs more than the
    /// better tree saves, and its build grows with every instanced triangle (docs/design.md,
    /// "World trees").
    bool world_tree = false;
    float world_tree_triangle_budget = 2.0f;
    std::uint32_t world_tree_max_instances = 100;
    std::uint64_t world_tree_max_triangles = 1000000;
    /// The world tree's build: the object builder's settings, spatial splits included.
    BuildSettings world_tree_build = static_object_build_settings();
};

/// A top level with the object nodes of its items copied in: one tree that a ray
/// traverses without entering those instances. An item of an instance placed by the identity
/// (an object built in world space, the paper's common case, §3.1) needs no ray of its own, so
/// the object subtree it names can hang below the top-level node that held the item, as a
/// subtree of a flat BVH would: the ray reaches those object nodes and leaves in the same loop
/// and with the same stack as the top level's nodes, and entering no longer chains the item,
/// its instance's record and its mesh's arrays before the first object node can be fetched.
/// An item that names an object leaf needs no copy: the leaf itself hangs in the item's slot
/// (its hint word naming the leaf's source), tested with its node's other leaves as a flat
/// BVH tests sibling leaves (traverse_bvh's LeafVisits::by_node, which visits items one by
/// one), where its box is small beside its node's (kHungLeafAreaShare) and the node's other
/// hung leaves are of the same instance; other such items stay items. Items of placed
/// instances are merged only where TopLevelMergeSettings::placed_instances asks (world-space
/// boxes over object-space triangles).
///
/// The copy holds the top level's nodes (same numbers, hung leaves in place of their items)
/// followed by each merged subtree's nodes; a copied object node keeps its leaf references,
/// which still name triangles in its mesh's leaf order, and its subtree's source says where
/// those are. The top level itself
/// (TopLevelBvh) is unchanged: statistics and structure hashes read it.
struct MergedTopLevel {
    /// The top bit of a hint word that names a source (its index in `sources` below the
    /// bit) instead of a child's rows. In a copied node every leaf or empty slot's word names
    /// the node's source, and a node of eight inner children gives up the hint of the child
    /// whose rows span the fewest lines for it, so that every copied node names its source;
    /// in a top-level node, the words of the slots where object leaves hang name theirs.
    static constexpr std::uint32_t kSourceWordFlag = 0x80000000u;
    /// An item naming an object leaf hangs that leaf in its slot only where the item's box
    /// takes at most this share of its node's area (half the surface). A hung leaf is tested
    /// at its node, before the ray goes on to the node's inner children, where an item waits
    /// on the stack behind nearer ones and is skipped when a nearer hit ends the ray first: a
    /// leaf that spans its node is entered by nearly every ray through it, mostly behind a
    /// nearer hit. The drop-in grid's ground plane (2 triangles under the whole scene, 0.94 of
    /// its node's area), hung, cost the grid's camera rays 7 % (docs/design.md, "Object
    /// leaves hung in the top level").
    static constexpr float kHungLeafAreaShare = 0.75f;

    std::vector<WideNode> nodes;
    /// Nodes from this id on are copied object nodes; below it, the top level's own, whose
    /// leaves are top-level items.
    std::uint32_t first_object_node = 0;
    /// Per merged subtree, in the order the copy holds them (the top level's node and slot
    /// order), then per instance whose leaves hang in the top level (in the order of its
    /// first hung leaf): where the leaves' triangles are and in which space.
    std::vector<MergedLeafSource> sources;
    /// Every source has pre-arranged rows: the SIMD kernels read rows only (one loop).
    bool every_source_has_rows = true;
    /// The top-level items the merge left in the tree are few enough that queries enter them
    /// out of line (TopLevelMergeSettings::items_out_of_line_area_share;
    /// TraceKernels::merged_rare_items_intersect).
    bool enters_items_out_of_line = false;
    /// Copied nodes from this id on ask for the leaf rows of the inner children the traversal
    /// descends into (their hint words, in their source's rows), as an object BVH's
    /// traversal does (LeafRowsPrefetch): from first_object_node where the structure's rows
    /// outgrow the caches (its views' ObjectBvhView::prefetches_rows), past every node
    /// elsewhere.
    std::uint32_t rows_prefetch_from = NodeRef::kEmptyBits;
    /// The top level's root; empty when nothing was merged (traversal takes the top level).
    NodeRef root = NodeRef::empty();
    /// Whether this is a world tree (world_tree.h), traced by its own queries: every leaf
    /// slot names its own source, where elsewhere a node's leaves share one.
    bool is_world_tree = false;
    /// A world tree's leaves (world_tree.h): its triangles, rows and primIDs in leaf order,
    /// which every source points into (its nodes are `nodes`); empty otherwise. The sources'
    /// pointers stay valid when the MergedTopLevel moves, not when it is copied.
    ObjectBvh world_tree_leaves;

    bool empty() const { return root.is_empty(); }
    bool is_object_node(std::uint32_t node_id) const { return node_id >= first_object_node; }
    /// The source of copied object node `node`'s leaf children, `leaf_slots` the mask of some
    /// of them (not empty): read from the node itself, whose leaf slots keep their source's
    /// index in the hint words leaf_row_hints leaves unused there (kSourceWordFlag), so that
    /// testing the leaves waits on no load beyond the node's own (a table per copied node
    /// missed the cache on large scenes).
    const MergedLeafSource& source_of_leaves(const WideNode& node, unsigned leaf_slots) const {
        return source_named_by(node.leaf_row_hints[std::countr_zero(leaf_slots)]);
    }
    /// Whether slot `slot` of top-level node `node` holds an item left to enter: a leaf whose
    /// hint word names no source.
    static bool holds_item(const WideNode& node, int slot) {
        return node.children[slot].is_leaf() && (node.leaf_row_hints[slot] & kSourceWordFlag) == 0;
    }
    /// The source a hint word carrying kSourceWordFlag names.
    const MergedLeafSource& source_named_by(std::uint32_t word) const {
        return sources[word & ~kSourceWordFlag];
    }
    std::uint64_t memory_bytes() const {
        return nodes.size() * sizeof(WideNode) + sources.size() * sizeof(MergedLeafSource) +
               world_tree_leaves.memory_bytes();
    }
};

/// The merge of `top`'s items (views[targets[instance].mesh] their BVH; only top-level leaves
/// of one item, the top builders' leaves) that name inner object nodes (their subtrees copied)
/// or object leaves (hung in place, where MergedTopLevel::kHungLeafAreaShare allows; not
/// where opening split leaves, TopLevelBvh::has_partial_leaves, since rows are laid out per
/// whole leaf), as `settings` choose: world-space items (InstanceTarget::kWorldSpace) when at
/// least half of the top's items are world-space items or the placed items merge too, items
/// of placed instances (placed by `object_to_world`, per instance) when their copies hold at
/// most placed_node_budget times `object_nodes` (the inner nodes of the scene's object BVHs)
/// nodes (a hung leaf copies none). An empty MergedTopLevel when nothing is merged, for a top level
/// whose root is a leaf, and where the copy would hold more nodes than a NodeRef can name. The
/// merged traversal costs every node a little more (the choice of leaf visit, the source of each
/// object leaf), which the entries saved repay where most items need no ray of their own;
/// where most entered placed instances, it did not (docs/design.md, "World-space items merged
/// into the top level"). Deterministic: subtrees and sources are placed in the top level's
/// node and slot order, whatever the thread count.
MergedTopLevel merge_top_level_items(const TopLevelBvh& top,
                                     std::span<const InstanceTarget> targets,
                                     std::span<const ObjectBvhView> views,
                                     std::span<const AffineTransform> object_to_world,
                                     std::uint64_t object_nodes,
                                     const TopLevelMergeSettings& settings = {});

}  // namespace rebraid
