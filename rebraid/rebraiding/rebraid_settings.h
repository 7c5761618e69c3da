#pragma once

#include <cstdint>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/rebraiding/bref_bounds.h"
#include "rebraid/top_level/merged_top_level.h"

namespace rebraid {

/// How the extra BRef space (the opening budget) is sized (paper §5.2).
enum class BudgetRule {
    /// budget = budget_factor x instances: the paper's rule for trees over instances.
    per_instance,
    /// budget = instanced primitives / primitives_per_bref: the paper's rule for trees over
    /// objects built in world space.
    per_primitive,
    /// The larger of the two: a few instances of large meshes (objects placed in world space,
    /// as the paper's Powerplant) get the per-primitive budget, many small instances the
    /// per-instance one. On the measured scenes only the generated powerplant differs from
    /// per_instance (224 -> 3,179 extra BRefs; 1.8x the diffuse rays per second).
    larger,
};

/// Which BRefs a segment opens (paper §4.2, and rules beyond the paper).
enum class OpeningRule {
    /// The paper's rule (§4.2): every inner-node BRef wider than `open_threshold` of the
    /// segment's extent along its largest axis; child primitive counts are estimated as the
    /// parent's divided by the number of children (§5.3).
    extent,
    /// The paper's candidates, opened only when the segment's estimated SAH falls
    /// (sah_aware_opening.h); child primitive counts are the object BVH's real ones.
    sah,
    /// Candidates chosen by how much of their box overlaps BRefs of other instances
    /// (overlap_opening.h), then the SAH test of `sah`.
    overlap,
};

/// Most doublings of the BRef budget the budget search makes (RebraidSettings).
inline constexpr std::uint32_t kMaxBudgetDoublings = 16;

/// Parameters of the re-braiding top-level builder (Benthin et al. 2017). Defaults: the paper's
/// threshold, budget and termination, with two rules beyond the paper that measured better on
/// every scene (bench/RESULTS.md): `sah` opening and BRef bounds from the
/// transformed vertices. paper_rules() gives the paper's rules alone.
struct RebraidSettings {
    /// A BRef is opened when its extent along the segment's largest axis exceeds this
    /// fraction of the segment's extent (paper §4.2: 10%). 0 opens every inner-node BRef
    /// (within the budget); 1 or more opens nothing.
    float open_threshold = 0.10f;
    /// Which rule sizes the budget.
    BudgetRule budget_rule = BudgetRule::larger;
    /// Extra BRefs per instance under BudgetRule::per_instance and larger (paper §5.2: 4). 0
    /// with per_instance gives the plain two-level top.
    float budget_factor = 4.0f;
    /// Instanced primitives per extra BRef under BudgetRule::per_primitive and larger (paper
    /// §5.2: 1000).
    float primitives_per_bref = 1000.0f;
    /// Budget search: when the build at the rule's budget spent it (see
    /// `budget_search_min_use`), build again with the budget doubled, and when that lowered
    /// the exact SAH cost (rebraid_cost_guard.h) by at least `budget_search_min_gain`, once
    /// more with the budget doubled this many times (x8 for 3); keep the cheapest build. 0
    /// builds once, at the rule's budget; 1 tries the doubled budget only. The paper notes
    /// that subtrees may run out of budget where objects overlap deep down (§7); on the shared
    /// scenes where the rule's budget was spent in full (brainstem, cg57_cruiser, powerplant)
    /// each doubling up to x8 lowered the cost (by 2-24 % of the part the top level's own
    /// nodes and boxes make); x4 traced 4-23 % faster than x1 (bench/RESULTS.md) and x8 cut
    /// the instructions per diffuse ray by a further 2.8, 3.4 and 14 % (callgrind). Where a
    /// doubling pays, the search goes on to the largest budget in one step rather than
    /// doubling again and again, for the same trees on those scenes at about two thirds of
    /// the search's builds (docs/design.md); where the first doubling does not pay (crown, the
    /// forest and the city under the paper's rules) it stops there. Per-frame tops of
    /// DynamicSceneAccel search no budgets.
    std::uint32_t budget_doublings = 3;
    /// Least cost reduction of the first doubling for the budget search to go on to the
    /// largest budget, relative to the part of the SAH cost the top level itself makes (its
    /// nodes and the boxes entering objects).
    float budget_search_min_gain = 0.01f;
    /// Beyond `budget_doublings`, the budget search doubles once more, and again, while the
    /// last build it kept filled its budget (`budget_search_min_use`) and each doubling
    /// lowered the exact cost by at least this fraction of the part the top level itself
    /// makes. The generated powerplant (objects in world space overlapping everywhere) fills
    /// x8 and x16 lowers its cost by 6.5 % of that part: 1.07x / 1.06x as fast on primary /
    /// diffuse rays as with x8, for 25 ms more top build (94 to 120 ms of a 770 ms build);
    /// cg57_cruiser fills x8 too, but x16 lowered its cost by 0.9 % and traced 3-5 % slower
    /// (more items naming object leaves, each entered): it stops at x8 (docs/design.md).
    float budget_search_extra_gain = 0.03f;
    /// The budget search builds again only after a build that filled at least this fraction of
    /// its budget: a build that left free space unused was not held back by its budget, and
    /// where nothing opens (forests, cities) a larger budget would only repeat the build. 0
    /// searches whatever the use.
    float budget_search_min_use = 0.95f;
    /// Hard cap on the extra BRefs, whatever the rule gives: the BRef array (40 bytes per
    /// BRef, plus as much again of build scratch) is allocated in full before the build
    /// starts, so a huge budget_factor must not turn into gigabytes. The default, 2^22 extra
    /// BRefs (160 MiB of array), is what the paper's factor of 4 needs for a million
    /// instances. At most 2^27 - 1 (the top level's item limit). See bref_budget() for the
    /// other cap.
    std::uint64_t max_budget = std::uint64_t(1) << 22;
    /// Segments with at most this many BRefs stop opening when their boxes overlap little
    /// (paper §4.4: 4).
    std::uint32_t small_segment_brefs = 4;
    /// "Little" overlap for that test: every pairwise intersection of the segment's BRef
    /// boxes has at most this fraction of the surface area of the smaller box.
    float small_overlap_fraction = 0.1f;
    /// World-space boxes of BRefs of transformed instances: the paper's transformed node box
    /// (§5.4), the tighter union of transformed children, or the box of the transformed
    /// vertices (bref_bounds.h).
    BRefBoundsRule bounds_rule = BRefBoundsRule::transformed_vertices;
    /// BRefBoundsRule::transformed_vertices: a mesh with at least this many instances in the
    /// build gets support tables (object_support_tables.h) for its root and the root's
    /// children, so that its BRefs' boxes cost a few table lookups rather than searches of
    /// its BVH. A table costs about 80 such searches and is a little looser (the grid's
    /// error, up to about 3 % of the extent, against 1 %), so it pays for meshes of many
    /// instances.
    std::uint32_t support_table_instances = 512;
    /// Which BRefs are opened (see OpeningRule).
    OpeningRule opening_rule = OpeningRule::sah;
    /// Also open BRefs to object-BVH leaves of several triangles, into one BRef per triangle
    /// (a leaf reference of count 1), when they meet the opening rule. For scenes of many tiny
    /// objects whose whole BVH is one leaf or a few.
    bool open_leaves = false;
    /// OpeningRule::sah and overlap: SAH cost of entering an instance through one more BRef
    /// (transforming the ray), per unit of the BRef's area, relative to one node visit. The
    /// SAH `rebraid stats` reports does not count it (0); a positive value makes opening more
    /// reluctant where many small BRefs would each cost a transform.
    float instance_entry_cost = 0.0f;
    /// OpeningRule::sah and overlap: wide top-level node levels the SAH estimate builds (by
    /// binned SAH, like the builder) over the BRefs with and without opening, before it
    /// assumes the nodes further down are as large as their parent. More levels judge large
    /// segments better and cost more build time.
    std::uint32_t estimate_levels = 2;
    /// OpeningRule::sah and overlap: estimate_levels for a segment whose BRefs all belong to
    /// instances placed by the identity (objects built in world space, the paper's case for
    /// unique meshes). Large world-space objects that overlap (an architectural scene's long
    /// pipes) gain from opening two levels further down than the instanced scenes measured:
    /// 4 levels there lowered the generated powerplant's SAH by 5.9 % (1.22x the diffuse
    /// rays per second) and crown's by 0.3 %, while for instanced scenes 3 levels already
    /// cost fzk_haus 1.6 % SAH and the forest 4x the top build (docs/design.md).
    std::uint32_t world_space_estimate_levels = 4;
    /// OpeningRule::sah and overlap: segments of more BRefs than this open nothing themselves
    /// and skip the estimate (the segments below them still may open, with the whole free
    /// space). A segment's candidates are the BRefs wider than open_threshold of its extent,
    /// and in large segments those rarely pay (on the measured scenes the largest segment that
    /// opened had 800 BRefs), while the estimate there costs a virtual build over all of
    /// them. Bounds the estimate work per BRef (docs/design.md).
    std::uint32_t estimate_max_brefs = 1024;
    /// OpeningRule::sah and overlap: a subtree stops opening once this many nested segments
    /// in a row (each inside the last) estimated that opening would not lower their SAH; 0
    /// never stops. Where instances barely overlap (a forest), every segment's estimate says
    /// no and the estimates were most of the build. 4 kept every measured scene's SAH within
    /// 0.3 % of never stopping; 3 and fewer cost fzk_haus over 1 % (docs/design.md).
    std::uint32_t estimate_give_up = 4;
    /// OpeningRule::sah and overlap: a segment of at least this many BRefs whose estimate says
    /// no stops its subtree's opening at once (0: only estimate_give_up stops it). A no from
    /// many BRefs is a no for the segments inside it with few exceptions, while estimating
    /// each of them again is most of a large build: on trees at 100,000 instances nearly every
    /// estimate says no and this cut the top build from 544 to 211 ms at the same SAH. 256
    /// changed no tree of the default scene or the shared scenes, and the generated scenes'
    /// SAH by at most 0.4 % (powerplant; docs/design.md).
    std::uint32_t estimate_give_up_brefs = 256;
    /// OpeningRule::sah and overlap: before estimating, a segment checks that boxes of two
    /// of its instances overlap (cross_instance_overlap.h); where none do, neither it nor any
    /// segment below it opens, and no estimate is made there. Re-braiding undoes overlap
    /// (paper §1, §4.2); where instances lie apart (a city of separate buildings) the
    /// estimates were nearly all of the build and opened for SAH gains of a few tenths of a
    /// percent (docs/design.md).
    bool require_overlap = true;
    /// OpeningRule::sah and overlap: when the build opened anything, also build the top
    /// without opening and keep whichever has the lower exact SAH cost
    /// (rebraid_cost_guard.h), so the rules never end above the unopened top. Costs one
    /// plain top-level build.
    bool keep_cheaper_unopened = true;
    /// When anything opened, build the tree again over the final BRefs (rebuild_top_tree):
    /// opening decides which BRefs there are, a plain binned-SAH build places them. The tree
    /// grown while opening made its upper splits over BRefs that opened only below those
    /// splits, and their children then reach across them. With the optimal cut (`build`), a
    /// diffuse ray's top-level node visits went from 15.8 to 11.1 on the generated powerplant
    /// and from 5.8 to 5.3 on brainstem (docs/design.md, "Building the tree again over the
    /// final BRefs", which also has the BRefs' weights, rebuilt_tree_weight), for one plain
    /// build over the kept BRefs (the budget search and the cost guard compare the trees
    /// grown while opening).
    bool rebuild_tree = true;
    /// Build each mesh that exactly one instance places, by a transform other than the
    /// identity, in world space (meshes_in_world_space in world_space_meshes.h): rays reach
    /// it without being mapped, and a top of mostly such objects is merged
    /// (merge_world_space). Its object BVH, and a located hit's corners, are then in world
    /// space. The Embree glue keeps object spaces, whose bits Embree's instanced hits have.
    bool world_space_single_instances = true;
    /// Also give each instance of a mesh that several instances place a world-space copy of
    /// its own, while the copies add at most this fraction of the scene's mesh triangles
    /// (the meshes whose copies add the fewest triangles first; 0: none). Instancing saves
    /// memory where a mesh repeats many times; a mesh placed two or four times saves little
    /// and costs each ray that reaches it a mapped ray. On
    /// two_cylinder_engine a quarter of its mesh triangles copies 13 of its 14 shared meshes
    /// (the 20 placements of its bolt stay instanced) and the top is merged: 1.05x / 1.07x as
    /// fast on primary / diffuse rays, at 8.6 instead of 6.6 MB (docs/design.md).
    float world_space_copy_budget = 0.25f;
    /// Merge the object subtrees that world-space BRefs name into the traced top level
    /// (MergedTopLevel): rays reach them without entering their instances.
    bool merge_world_space = true;
    /// Merge those of BRefs of placed instances too, with world-space boxes over triangles
    /// tested in object space (TopLevelMergeSettings::placed_instances), while their copies
    /// hold at most merge_placed_node_budget times the object BVHs' inner nodes. Off: it paid
    /// under the Embree glue, which keeps every mesh in object space, and was not measured to
    /// pay where meshes placed once are built in world space (docs/design.md).
    bool merge_placed_instances = false;
    float merge_placed_node_budget = 1.0f;
    /// Where the items left in the merged tree have boxes whose areas add up to at most this
    /// share of the root's, queries enter them out of line
    /// (TopLevelMergeSettings::items_out_of_line_area_share).
    float merge_items_out_of_line_area_share = 0.5f;
    /// Trace a world tree instead (TopLevelMergeSettings::world_tree; world_tree.h): one BVH
    /// over every instance's triangles, built in world space with spatial splits of
    /// `world_tree_spatial_split_budget`, whose leaves keep their instance's object space,
    /// for scenes of at most `world_tree_max_instances` instances and
    /// `world_tree_max_triangles` instanced triangles, those at most
    /// `world_tree_triangle_budget` times the meshes'. The top level and the object BVHs are
    /// still built (the structure's hash, updates); the world tree is what queries traverse.
    /// Off: the project's own structures build meshes placed once in world space and merge
    /// them.
    bool world_tree = false;
    float world_tree_triangle_budget = 2.0f;
    std::uint32_t world_tree_max_instances = 100;
    std::uint32_t world_tree_max_triangles = 1000000;
    float world_tree_spatial_split_budget = kStaticSpatialSplitBudget;
    /// OpeningRule::overlap: a BRef is a candidate when the boxes of BRefs of other instances
    /// cover at least this fraction of its box (estimated on a grid over the segment).
    float overlap_threshold = 0.25f;
    /// Binning, SAH costs and the serial threshold of the top-level build (leaves hold one
    /// BRef: max_leaf_size is 1). Subtrees of 32 BRefs and more are tasks of their own (an
    /// object build's threshold is 1,024 primitives): a BRef costs microseconds here (opening
    /// estimates, children's vertex bounds), and at 1,024 a top of a few hundred instances
    /// ran on one thread. The tree does not depend on it. The tree grown while opening fills
    /// its nodes greedily, as the plain top level's (default_top_level_settings()); `collapse`
    /// chooses the cut of the rebuilt tree (rebuild_tree) and of IncrementalTopLevel's upper
    /// tree, optimal by default: over opened BRefs it visited 2-4 % fewer nodes than the
    /// greedy cut and traced faster on every scene that opens but fzk_haus (docs/design.md).
    BuildSettings build{
        .max_leaf_size = 1, .task_threshold = 32, .collapse = NodeCollapse::optimal};

    /// What the traced tree merges (InstancedAccel's `merge`).
    TopLevelMergeSettings merge_settings() const {
        TopLevelMergeSettings merge{
            .world_space = merge_world_space,
            .placed_instances = merge_placed_instances,
            .placed_node_budget = merge_placed_node_budget,
            .items_out_of_line_area_share = merge_items_out_of_line_area_share,
            .world_tree = world_tree,
            .world_tree_triangle_budget = world_tree_triangle_budget,
            .world_tree_max_instances = world_tree_max_instances,
            .world_tree_max_triangles = world_tree_max_triangles};
        merge.world_tree_build.spatial_split_budget = world_tree_spatial_split_budget;
        return merge;
    }

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;

    /// The paper's rules alone: the extent opening rule (§4.2) with estimated child counts
    /// (§5.3) and transformed node boxes (§5.4); everything else as the defaults.
    static RebraidSettings paper_rules() {
        RebraidSettings settings;
        settings.bounds_rule = BRefBoundsRule::transformed_box;
        settings.opening_rule = OpeningRule::extent;
        return settings;
    }
};

}  // namespace rebraid
