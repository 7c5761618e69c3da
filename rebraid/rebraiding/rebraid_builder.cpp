#include "rebraid/rebraiding/rebraid_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/fit_inner_boxes.h"
#include "rebraid/bvh/object_subtree_counts.h"
#include "rebraid/bvh/object_support_tables.h"
#include "rebraid/bvh/wide_tree_grower.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"
#include "rebraid/core/huge_pages.h"
#include "rebraid/core/parallel_blocks.h"
#include "rebraid/core/scratch_buffer.h"
#include "rebraid/core/zeroed_buffer.h"
#include "rebraid/rebraiding/bref.h"
#include "rebraid/rebraiding/bref_budget.h"
#include "rebraid/rebraiding/bref_opening.h"
#include "rebraid/rebraiding/cross_instance_overlap.h"
#include "rebraid/rebraiding/overlap_opening.h"
#include "rebraid/rebraiding/rebraid_cost_guard.h"
#include "rebraid/rebraiding/rebraid_termination.h"
#include "rebraid/rebraiding/sah_aware_opening.h"
#include "rebraid/rebraiding/top_tree_rebuild.h"
#include "rebraid/top_level/bvh_stats.h"

namespace rebraid {
namespace {

/// A segment after its opening step, ready to become a leaf or to be split.
struct RebraidCandidate {
    BRefSegment segment;
    RangeInfo info;
    BinnedSplit split;
    bool is_leaf = true;
    float half_area = 0.0f;  ///< info.bounds.half_area(), which node growth compares often

    float area() const { return half_area; }
    BBox3f bounds() const { return info.bounds; }
    std::size_t size() const { return segment.size(); }
};

/// The re-braiding steps of §4.1 for one segment, as the policy of WideTreeGrower. Each
/// split measures both children while partitioning and scans each child once for all the
/// opening decisions (free-space share, termination, whether anything can open), so a
/// level reads each BRef in four passes (partition, scan, open, bin) rather than seven.
class RebraidPolicy {
public:
    RebraidPolicy(std::span<BuildPrim> prims, std::span<BuildPrim> scratch,
                  std::span<BRefTarget> targets, const BRefSource& source,
                  const RebraidSettings& settings)
        : prims_(prims),
          scratch_(scratch),
          targets_(targets),
          source_(source),
          settings_(settings),
          world_space_settings_(settings) {
        world_space_settings_.estimate_levels = settings.world_space_estimate_levels;
    }

    /// Steps (1)-(2): termination tests (§4.4), then opening (§4.2, §5.3); then the SAH split
    /// search of step (3) (§4.3). `info` describes the segment's BRefs; `scan` is their
    /// opening scan under the segment's criterion when the caller already made it.
    RebraidCandidate prepare(BRefSegment segment, RangeInfo info, std::optional<OpeningScan> scan,
                             bool median_only) const {
        const std::size_t threshold = settings_.build.parallel_threshold;
        if (segment.can_open && segment.free_space() > 0) {
            const OpeningCriterion criterion = criterion_for(info.bounds);
            if (!scan) scan = scan_for_opening(range(segment), targets_, criterion, threshold);
            if (scan->is_single_instance ||
                (segment.size() <= settings_.small_segment_brefs &&
                 overlaps_little(range(segment), settings_.small_overlap_fraction))) {
                segment.can_open = false;
            } else if (scan->openable > 0) {  // otherwise no rule opens anything
                const std::uint32_t opened = open_segment(segment, criterion, info);
                opened_ += opened;
            }
        }
        // Built field by field rather than zeroed and overwritten: prepare runs once per
        // BRef and then some.
        const std::uint32_t n = segment.size();
        const float area = info.bounds.half_area();
        BinnedSplit split;
        bool is_leaf = true;
        if (n > 1) {
            if (!median_only) split = find_binned_split(range(segment), info, settings_.build);
            is_leaf = n <= settings_.build.max_leaf_size;
            if (split.is_valid() && is_leaf) {
                const float leaf_cost =
                    settings_.build.intersection_cost * area * float(info.weight);
                const float split_cost = settings_.build.traversal_cost * area +
                                         settings_.build.intersection_cost * split.cost;
                is_leaf = leaf_cost <= split_cost;
            }
        }
        return {segment, info, split, is_leaf, area};
    }

    /// Step (3)-(4): partition, share the free space (§5.2), prepare both children.
    std::array<RebraidCandidate, 2> split(const RebraidCandidate& c, bool median_only) const {
        const BRefSegment& segment = c.segment;
        const std::size_t threshold = settings_.build.parallel_threshold;
        std::uint32_t mid = segment.start + segment.size() / 2;
        RangeInfo left_info, right_info;
        if (c.split.is_valid()) {
            // Measures both sides on the way; each task's segments own the same part of the
            // scratch buffer as of the BRef array.
            const SplitResult result =
                apply_binned_split(range(segment), c.split,
                                   scratch_.subspan(segment.start, segment.size()), threshold);
            mid = segment.start + result.left_count;
            left_info = result.left;
            right_info = result.right;
        } else {
            left_info =
                compute_range_info(prims_.subspan(segment.start, mid - segment.start), threshold);
            right_info = compute_range_info(prims_.subspan(mid, segment.end - mid), threshold);
        }
        BRefSegment left{segment.start,           mid, mid, segment.next_target, segment.can_open,
                         segment.failed_estimates};
        BRefSegment right{mid,
                          segment.end,
                          segment.end,
                          segment.next_target,
                          segment.can_open,
                          segment.failed_estimates};
        std::optional<OpeningScan> left_scan, right_scan;
        if (segment.can_open && segment.free_space() > 0) {
            left_scan = scan_for_opening(prims_.subspan(segment.start, mid - segment.start),
                                         targets_, criterion_for(left_info.bounds), threshold);
            right_scan = scan_for_opening(prims_.subspan(mid, segment.end - mid), targets_,
                                          criterion_for(right_info.bounds), threshold);
            std::tie(left, right) =
                split_free_space(segment, mid, left_scan->openable, right_scan->openable, prims_);
        }
        return {prepare(left, left_info, left_scan, median_only),
                prepare(right, right_info, right_scan, median_only)};
    }

    NodeRef make_leaf(const RebraidCandidate& c) const {
        return NodeRef::leaf(c.segment.start, c.segment.size());
    }

    std::uint64_t opened() const { return opened_; }

private:
    OpeningCriterion criterion_for(const BBox3f& bounds) const {
        return OpeningCriterion(bounds, settings_.open_threshold, settings_.open_leaves);
    }

    /// Step (2): opens the BRefs the settings' rule picks (§4.2, §5.3, or the overlap and
    /// SAH-aware rules beyond the paper) and updates `info` when it did; returns how many.
    std::uint32_t open_segment(BRefSegment& segment, OpeningCriterion criterion,
                               RangeInfo& info) const {
        const std::size_t threshold = settings_.build.parallel_threshold;
        std::vector<std::uint8_t> overlapping;
        if (settings_.opening_rule != OpeningRule::extent) {
            // The cheap reasons not to estimate first, before any per-segment grid.
            if (segment.size() > settings_.estimate_max_brefs)
                return 0;  // the segments below may still open
            if (settings_.require_overlap &&
                !has_cross_instance_overlap(range(segment), targets_)) {
                segment.can_open = false;  // nor can any segment below: cross_instance_overlap.h
                return 0;
            }
            if (settings_.opening_rule == OpeningRule::overlap) {
                overlapping = select_overlapping(range(segment), targets_, info.bounds,
                                                 settings_.overlap_threshold);
                criterion.selected = overlapping;
            }
            if (!estimate_opening(range(segment), info, targets_, criterion, source_,
                                  segment.free_space(), estimate_settings(segment))
                     .lowers_sah()) {
                // The subtree below may still open (its segments are smaller), unless the
                // estimates have said no often enough in a row, or once for many BRefs.
                ++segment.failed_estimates;
                const bool is_large = settings_.estimate_give_up_brefs > 0 &&
                                      segment.size() >= settings_.estimate_give_up_brefs;
                const bool said_no_often = settings_.estimate_give_up > 0 &&
                                           segment.failed_estimates >= settings_.estimate_give_up;
                if (is_large || said_no_often) segment.can_open = false;
                return 0;
            }
            segment.failed_estimates = 0;
        }
        return open_brefs(segment, prims_, targets_, criterion, source_, threshold, &info);
    }

    /// The settings the segment's SAH estimate uses: world_space_estimate_levels when every
    /// BRef belongs to an instance placed by the identity (a scan that stops at the first
    /// that is not, the first BRef on instanced scenes).
    const RebraidSettings& estimate_settings(const BRefSegment& segment) const {
        for (const BuildPrim& prim : range(segment))
            if (!(source_.object_to_world(targets_[prim.id].instance_id) ==
                  AffineTransform::identity()))
                return settings_;
        return world_space_settings_;
    }

    std::span<BuildPrim> range(const BRefSegment& s) const {
        return prims_.subspan(s.start, s.size());
    }

    std::span<BuildPrim> prims_;
    std::span<BuildPrim> scratch_;
    std::span<BRefTarget> targets_;
    const BRefSource& source_;
    const RebraidSettings& settings_;
    RebraidSettings world_space_settings_;  ///< settings_ with world_space_estimate_levels
    // A statistic only: the sum is the same whatever order the tasks add in.
    mutable std::atomic<std::uint64_t> opened_{0};
};

/// Per mesh, the ObjectSupportTables of its BVH where the settings ask for vertex bounds and
/// the mesh has support_table_instances `instances` of `scene` or more (others: no tables);
/// empty when no mesh has.
std::vector<ObjectSupportTables> object_support_tables(const Scene& scene,
                                                       std::span<const ObjectBvh> object_bvhs,
                                                       std::span<const InstanceId> instances,
                                                       const RebraidSettings& settings) {
    if (settings.bounds_rule != BRefBoundsRule::transformed_vertices) return {};
    std::vector<std::uint32_t> uses(object_bvhs.size(), 0);
    for (const InstanceId i : instances) ++uses[scene.instances[i].mesh_id];
    std::vector<std::uint32_t> meshes;
    for (std::uint32_t mesh = 0; mesh < uses.size(); ++mesh)
        if (uses[mesh] >= settings.support_table_instances) meshes.push_back(mesh);
    if (meshes.empty()) return {};
    std::vector<ObjectSupportTables> tables(object_bvhs.size());
    tbb::parallel_for(std::size_t(0), meshes.size(), [&](std::size_t k) {
        tables[meshes[k]] = ObjectSupportTables(object_bvhs[meshes[k]]);
    });
    return tables;
}

/// What every build of one build_rebraid call starts from, made once: the budget search and
/// the cost guard build again over the same instances with the same bounds rule, and the
/// seed BRefs' world boxes (vertex bounds: searches of the object BVHs) are most of what a
/// build without opening costs.
struct RebraidInputs {
    std::span<const ObjectBvh> object_bvhs;
    std::span<const Instance> instances;              ///< the scene's; index = InstanceId
    std::vector<ObjectSupportTables> support_tables;  ///< see object_support_tables
    /// One seed BRef per instance of a non-empty mesh, at its object root (§3.2), in the
    /// order of the instances asked for: its instance, world box and, when costs are
    /// tracked, its root's cost inside the instance (rebraid_cost_guard.h).
    std::vector<InstanceId> seeded;
    std::vector<BBox3f> seed_bounds;
    std::vector<double> seed_cost;
    /// Triangle references of the seeded instances' object BVHs (a triangle cut by spatial
    /// splits once per part: each can become a BRef of its own).
    std::uint64_t primitive_count = 0;
};

RebraidInputs rebraid_inputs(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                             std::span<const InstanceId> instances, const RebraidSettings& settings,
                             bool is_tracking_cost) {
    RebraidInputs inputs;
    inputs.object_bvhs = object_bvhs;
    inputs.instances = scene.instances;
    reserve_on_huge_pages(inputs.seeded, instances.size());
    for (const InstanceId i : instances) {
        const ObjectBvh& bvh = object_bvhs[scene.instances[i].mesh_id];
        if (bvh.root.is_empty()) continue;
        inputs.seeded.push_back(i);
        inputs.primitive_count += bvh.prim_count();
    }
    const std::uint64_t limit = NodeRef::kMaxFirst;
    if (inputs.seeded.size() > limit)
        throw Error("build_rebraid: " + std::to_string(inputs.seeded.size()) +
                    " instances exceed the limit of " + std::to_string(limit));
    inputs.support_tables = object_support_tables(scene, object_bvhs, instances, settings);
    const std::size_t n = inputs.seeded.size();
    reserve_on_huge_pages(inputs.seed_bounds, n);
    inputs.seed_bounds.resize(n);
    if (is_tracking_cost) {
        reserve_on_huge_pages(inputs.seed_cost, n);
        inputs.seed_cost.resize(n);
    }
    auto seed = [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const InstanceId i = inputs.seeded[k];
            const std::uint32_t mesh = scene.instances[i].mesh_id;
            const ObjectBvh& bvh = object_bvhs[mesh];
            const AffineTransform& to_world = scene.instances[i].object_to_world;
            inputs.seed_bounds[k] = bref_world_bounds(
                bvh, bvh.root, bvh.bounds, to_world, settings.bounds_rule,
                inputs.support_tables.empty() ? nullptr : &inputs.support_tables[mesh]);
            if (is_tracking_cost)
                inputs.seed_cost[k] = mapped_box_half_area(bvh.bounds, to_world) *
                                      (bvh.root.is_leaf() ? bvh.root.prim_count() : 1.0);
        }
    };
    if (settings.bounds_rule == BRefBoundsRule::transformed_vertices) {
        // A seed's box may cost searches of its object BVH (microseconds): worth a task per
        // few of them. Each seed writes its own slot, so the split does not matter.
        constexpr std::size_t kSearchedSeedsPerTask = 16;
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, n, kSearchedSeedsPerTask),
            [&](const tbb::blocked_range<std::size_t>& r) { seed(0, r.begin(), r.end()); });
    } else if (n < settings.build.parallel_threshold) {
        seed(0, 0, n);
    } else {
        for_each_block(n, seed);
    }
    return inputs;
}

/// Leaves reference the BRef array with its unused free space in between; renumber them into
/// a dense item list (in array order) and fill the top level's items.
/// `item_slots` receives each item's target slot and `item_primitives` the primitives it stands
/// for. The used slots are marked in a bitmap (one bit per slot of the array, which the budget
/// can make several times the items) and counted per 64-bit word, so the pass reads the items,
/// not the free space.
void emit_items(TopLevelBvh& top, std::span<const BuildPrim> prims,
                std::span<const BRefTarget> targets, std::vector<std::uint32_t>& item_slots,
                std::vector<std::uint32_t>& item_primitives, std::size_t parallel_threshold) {
    const std::size_t words = (prims.size() + 63) / 64;
    std::vector<std::uint64_t> used(words, 0);
    auto mark = [&](NodeRef ref) {
        for (std::uint32_t i = ref.first_prim(); i < ref.first_prim() + ref.prim_count(); ++i)
            used[i >> 6] |= std::uint64_t(1) << (i & 63);
    };
    if (top.root.is_leaf()) mark(top.root);
    for (const WideNode& node : top.nodes)
        for (NodeRef ref : node.children)
            if (ref.is_leaf()) mark(ref);
    std::vector<std::uint32_t> word_start(words + 1, 0);
    for (std::size_t w = 0; w < words; ++w)
        word_start[w + 1] = word_start[w] + std::uint32_t(std::popcount(used[w]));
    const std::uint32_t count = word_start[words];
    reserve_on_huge_pages(top.items, count);
    reserve_on_huge_pages(top.item_bounds, count);
    reserve_on_huge_pages(item_slots, count);
    reserve_on_huge_pages(item_primitives, count);
    top.items.resize(count);
    top.item_bounds.resize(count);
    item_slots.resize(count);
    item_primitives.resize(count);
    auto fill = [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t w = begin; w < end; ++w) {
            std::uint32_t item = word_start[w];
            for (std::uint64_t bits = used[w]; bits != 0; bits &= bits - 1, ++item) {
                const BuildPrim& prim = prims[w * 64 + std::size_t(std::countr_zero(bits))];
                item_slots[item] = prim.id;
                item_primitives[item] = prim.weight;
                top.items[item] = targets[prim.id];
                top.item_bounds[item] = prim.bounds;
            }
        }
    };
    if (count < parallel_threshold)
        fill(0, 0, words);
    else
        for_each_block(words, fill);
    auto renumber = [&](NodeRef ref) {
        const std::uint32_t first = ref.first_prim();
        const std::uint64_t below = used[first >> 6] & ((std::uint64_t(1) << (first & 63)) - 1);
        return NodeRef::leaf(word_start[first >> 6] + std::uint32_t(std::popcount(below)),
                             ref.prim_count());
    };
    if (top.root.is_leaf()) top.root = renumber(top.root);
    for (WideNode& node : top.nodes)
        for (NodeRef& ref : node.children)
            if (ref.is_leaf()) ref = renumber(ref);
}

/// A build and, when tracked, its cost up to a constant of the instance set (see
/// rebraid_cost_guard.h).
struct TrackedBuild {
    RebraidBuild build;
    double cost = 0.0;
    std::vector<std::uint32_t> item_primitives;  ///< primitives each item stands for
};

/// Whether a build needs its cost. The cost guard compares a build that opened something;
/// the budget search compares one that used budget_search_min_use of its budget, which
/// without opening only a budget of 0 or a least use of 0 does. A first build that did
/// neither is compared with nothing, and at a million instances the sum over the budget's
/// slots was a pass of its own.
enum class CostNeed { none, if_compared, always };

TrackedBuild build_rebraid_once(const RebraidInputs& inputs, const RebraidSettings& settings,
                                CostNeed cost_need);

/// The budget search (RebraidSettings::budget_doublings): `first` is the tracked build at the
/// rule's budget. When it used at least budget_search_min_use of its budget, the budget is
/// doubled once; when that lowered the exact cost by at least budget_search_min_gain (and the
/// doubled budget was used as well), the search goes straight to the rule's budget doubled
/// budget_doublings times. The cheapest build tried is returned. The budgets tried and the
/// costs compared depend on the input only, so the choice is the same on any thread count.
TrackedBuild search_larger_budgets(const RebraidInputs& inputs, const RebraidSettings& settings,
                                   TrackedBuild first) {
    const std::uint64_t seeds = inputs.seeded.size();
    // The same test as build_rebraid_once's for whether a build's cost was taken.
    const auto used_its_budget = [&](const RebraidBuild& build) {
        return double(build.brefs - seeds) >=
               double(settings.budget_search_min_use) * double(build.budget);
    };
    if (!used_its_budget(first.build)) return first;
    // Both rules' budgets grow by the same factor, so a multiple of the settings' budget
    // multiplies whichever rule gives it. The caps (every primitive a BRef, max_budget, the
    // item limit) may leave no larger budget to try.
    std::uint64_t last_budget = first.build.budget;
    const auto build_times = [&](std::uint32_t doublings) -> std::optional<TrackedBuild> {
        RebraidSettings larger = settings;
        const float factor = std::ldexp(1.0f, int(doublings));
        larger.budget_factor *= factor;
        larger.primitives_per_bref = std::max(1.0f, larger.primitives_per_bref / factor);
        const std::uint64_t budget = std::min(bref_budget(larger, seeds, inputs.primitive_count),
                                              NodeRef::kMaxFirst - seeds);
        if (budget <= last_budget) return std::nullopt;
        last_budget = budget;
        return build_rebraid_once(inputs, larger, CostNeed::always);
    };
    std::optional<TrackedBuild> doubled = build_times(1);
    if (!doubled) return first;
    // The gain is measured against the part of the cost a top level owns (its nodes and the
    // boxes that enter the objects): the tracked costs are exact up to a constant.
    const bool doubling_pays =
        first.cost - doubled->cost >=
        double(settings.budget_search_min_gain) * top_level_own_cost(first.build.top);
    const bool doubled_used_its_budget = used_its_budget(doubled->build);
    TrackedBuild best = doubled->cost < first.cost ? std::move(*doubled) : std::move(first);
    if (settings.budget_doublings < 2 || !doubling_pays || !doubled_used_its_budget) return best;
    std::optional<TrackedBuild> largest = build_times(settings.budget_doublings);
    if (!largest || !(largest->cost < best.cost)) return best;
    best = std::move(*largest);
    // Beyond it, one doubling at a time while the last build filled its budget and each
    // doubling pays by budget_search_extra_gain of the top's own cost (powerplant).
    for (std::uint32_t doublings = settings.budget_doublings + 1;
         doublings <= kMaxBudgetDoublings && used_its_budget(best.build); ++doublings) {
        std::optional<TrackedBuild> more = build_times(doublings);
        if (!more || best.cost - more->cost < double(settings.budget_search_extra_gain) *
                                                  top_level_own_cost(best.build.top))
            break;
        best = std::move(*more);
    }
    return best;
}

}  // namespace

RebraidBuild build_rebraid(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                           const RebraidSettings& settings) {
    std::vector<InstanceId> every_instance(scene.instances.size());
    for (std::size_t i = 0; i < every_instance.size(); ++i) every_instance[i] = InstanceId(i);
    return build_rebraid(scene, object_bvhs, settings, every_instance);
}

RebraidBuild build_rebraid(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                           const RebraidSettings& settings, std::span<const InstanceId> instances) {
    settings.validate();
    if (object_bvhs.size() != scene.meshes.size())
        throw Error("build_rebraid: " + std::to_string(object_bvhs.size()) + " object BVHs for " +
                    std::to_string(scene.meshes.size()) + " meshes");
    for (const InstanceId i : instances)
        if (i >= scene.instances.size())
            throw Error("build_rebraid: instance " + std::to_string(i) + " of a scene with " +
                        std::to_string(scene.instances.size()) + " instances");
    const BuildTimer timer;
    const bool is_guarded =
        settings.opening_rule != OpeningRule::extent && settings.keep_cheaper_unopened;
    const bool is_searching = settings.budget_doublings > 0;
    const RebraidInputs inputs =
        rebraid_inputs(scene, object_bvhs, instances, settings, is_guarded || is_searching);
    TrackedBuild result = build_rebraid_once(
        inputs, settings, is_guarded || is_searching ? CostNeed::if_compared : CostNeed::none);
    if (is_searching) result = search_larger_budgets(inputs, settings, std::move(result));
    if (is_guarded && result.build.opened > 0) {
        // The opening rules estimate; the guard measures: the same instances without any
        // opening, kept when its exact cost is not higher.
        RebraidSettings unopened = settings;
        unopened.opening_rule = OpeningRule::extent;
        unopened.budget_rule = BudgetRule::per_instance;
        unopened.budget_factor = 0.0f;
        TrackedBuild plain = build_rebraid_once(inputs, unopened, CostNeed::always);
        if (plain.cost <= result.cost) {
            plain.build.budget = result.build.budget;
            result = std::move(plain);
        }
    }
    // The budgets and the guard compared the trees grown while opening; only the kept one is
    // built again (RebraidSettings::rebuild_tree). Where nothing opened, the tree grown is
    // already the plain build over the seeds.
    if (settings.rebuild_tree && result.build.opened > 0)
        rebuild_top_tree(result.build.top, result.item_primitives, settings.build);
    result.build.top.has_partial_leaves = settings.open_leaves;
    result.build.top.build_ms = timer.elapsed_ms();
    return std::move(result.build);
}

namespace {

/// One top-level build; build_rebraid has checked the inputs.
TrackedBuild build_rebraid_once(const RebraidInputs& inputs, const RebraidSettings& settings,
                                CostNeed cost_need) {
    const bool is_tracking_cost = cost_need != CostNeed::none;
    const std::span<const ObjectBvh> object_bvhs = inputs.object_bvhs;
    const auto n = std::uint32_t(inputs.seeded.size());

    // §5.2: one array for every BRef the build can ever hold, allocated once.
    RebraidBuild result;
    const std::uint64_t limit = NodeRef::kMaxFirst;
    result.budget =
        std::min(bref_budget(settings, n, inputs.primitive_count), limit - std::uint64_t(n));
    const auto capacity = std::uint32_t(n + result.budget);
    // Uninitialised: a slot is written before any segment holds it (free space is filled by
    // opening), and only slots that leaves hold are read at the end.
    const ScratchBuffer<BuildPrim> prim_buffer(capacity), scratch_buffer(capacity);
    const ScratchBuffer<BRefTarget> target_buffer(capacity);
    const std::span<BuildPrim> prims = prim_buffer.span();
    const std::span<BRefTarget> targets = target_buffer.span();
    // Zero for every slot no BRef reaches (see ZeroedBuffer: untouched slots cost nothing).
    const ZeroedBuffer<double> node_cost_buffer(is_tracking_cost ? capacity : 0);
    const ZeroedBuffer<double> removed_cost_buffer(is_tracking_cost ? capacity : 0);
    const std::span<double> node_cost = node_cost_buffer.span();
    const std::span<double> removed_cost = removed_cost_buffer.span();
    BRefSource source{object_bvhs,  inputs.instances,     settings.bounds_rule,
                      nullptr,      settings.open_leaves, node_cost,
                      removed_cost, inputs.support_tables};
    // One BRef per instance at its object root, with the root's primitive count (§3.2).
    auto seed = [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t slot = begin; slot < end; ++slot) {
            const InstanceId i = inputs.seeded[slot];
            const ObjectBvh& bvh = object_bvhs[inputs.instances[i].mesh_id];
            targets[slot] = {i, bvh.root};
            prims[slot] = {inputs.seed_bounds[slot], std::uint32_t(slot), bvh.prim_count()};
            if (is_tracking_cost) node_cost[slot] = inputs.seed_cost[slot];
        }
    };
    if (n < settings.build.parallel_threshold)
        seed(0, 0, n);
    else
        for_each_block(n, seed);

    // The paper's rule estimates child counts (§5.3); the others use the real ones, counted
    // for the meshes whose BRefs open.
    std::optional<LazySubtreeCounts> subtree_counts;
    std::optional<BRefChildBounds> child_bounds;
    if (settings.opening_rule != OpeningRule::extent) {
        subtree_counts.emplace(object_bvhs);
        source.subtree_counts = &*subtree_counts;
        // The SAH-aware rules ask for a candidate's children at each level it is one.
        child_bounds.emplace(capacity);
        source.child_bounds = &*child_bounds;
    }
    const RebraidPolicy policy(prims, scratch_buffer.span(), targets, source, settings);
    const std::size_t threshold = settings.build.parallel_threshold;
    const RebraidCandidate root =
        policy.prepare(BRefSegment{0, n, capacity, n, true},
                       compute_range_info(prims.first(n), threshold), {}, false);
    TopLevelBvh& top = result.top;
    top.bounds = root.info.bounds;
    // Node numbering as grow_wide_subtree's with the parallel threshold; tasks as fine as
    // the object builder's, and none on one thread (where the tree then needs no
    // renumbering pass). The tree is the same either way.
    const std::size_t threads = std::min<std::size_t>(
        tbb::this_task_arena::max_concurrency(),
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    const std::size_t task_threshold =
        threads > 1 ? settings.build.task_threshold : std::numeric_limits<std::size_t>::max();
    const WideTreeGrower<RebraidPolicy, RebraidCandidate> grower(policy, threshold, task_threshold);
    if (n > 0) top.root = root.is_leaf ? policy.make_leaf(root) : grower.grow(root, top.nodes);
    // BRefs opened below a node after its box was written may reach past it by rounding.
    top.bounds.extend(fit_inner_boxes(top.nodes, top.root));
    std::vector<std::uint32_t> item_slots, item_primitives;
    emit_items(top, prims, targets, item_slots, item_primitives, settings.build.parallel_threshold);
    result.brefs = top.items.size();
    result.opened = policy.opened();
    TrackedBuild tracked{std::move(result), 0.0, std::move(item_primitives)};
    const bool may_be_compared =
        tracked.build.opened > 0 ||
        double(tracked.build.brefs - n) >=
            double(settings.budget_search_min_use) * double(tracked.build.budget);
    if (cost_need == CostNeed::always || (cost_need == CostNeed::if_compared && may_be_compared))
        tracked.cost = cost_above_objects(tracked.build.top, item_slots, node_cost, removed_cost);
    return tracked;
}

}  // namespace

}  // namespace rebraid
