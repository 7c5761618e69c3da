#include "rebraid/rebraid_builder.h"

#include <tbb/parallel_for.h>

#include <array>
#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "rebraid/binned_split.h"
#include "rebraid/bref.h"
#include "rebraid/bref_budget.h"
#include "rebraid/bref_opening.h"
#include "rebraid/build_timer.h"
#include "rebraid/bvh_stats.h"
#include "rebraid/error.h"
#include "rebraid/object_subtree_counts.h"
#include "rebraid/overlap_opening.h"
#include "rebraid/parallel_partition.h"
#include "rebraid/rebraid_cost_guard.h"
#include "rebraid/rebraid_termination.h"
#include "rebraid/sah_aware_opening.h"
#include "rebraid/wide_node_growth.h"

namespace rebraid {
namespace {

/// A segment after its opening step, ready to become a leaf or to be split.
struct RebraidCandidate {
    BRefSegment segment;
    RangeInfo info;
    BinnedSplit split;
    bool is_leaf = true;

    float area() const { return info.bounds.half_area(); }
    BBox3f bounds() const { return info.bounds; }
    std::size_t size() const { return segment.size(); }
};

/// The re-braiding steps of §4.1 for one segment, as the policy of grow_wide_subtree.
class RebraidPolicy {
public:
    RebraidPolicy(std::span<BuildPrim> prims, std::span<BRefTarget> targets,
                  const BRefSource& source, const RebraidSettings& settings)
        : prims_(prims), targets_(targets), source_(source), settings_(settings) {}

    /// Steps (1)-(2): termination tests (§4.4), then opening (§4.2, §5.3); then the SAH split
    /// search of step (3) (§4.3). `info` may carry the segment's bounds when already known.
    RebraidCandidate prepare(BRefSegment segment, bool median_only,
                             std::optional<RangeInfo> info = {}) const {
        const std::size_t threshold = settings_.build.parallel_threshold;
        if (segment.can_open && segment.free_space() > 0) {
            if (all_same_instance(range(segment), targets_) ||
                (segment.size() <= settings_.small_segment_brefs &&
                 overlaps_little(range(segment), settings_.small_overlap_fraction))) {
                segment.can_open = false;
            } else {
                if (!info) info = compute_range_info(range(segment), threshold);
                const std::uint32_t opened = open_segment(segment, info->bounds);
                if (opened > 0) {
                    opened_ += opened;
                    info.reset();  // the BRefs changed
                }
            }
        }
        RebraidCandidate c{
            segment, info ? *info : compute_range_info(range(segment), threshold), {}, true};
        const std::uint32_t n = segment.size();
        if (n <= 1) return c;
        if (!median_only) c.split = find_binned_split(range(segment), c.info, settings_.build);
        if (!c.split.is_valid()) {
            c.is_leaf = n <= settings_.build.max_leaf_size;
            return c;
        }
        const float area = c.info.bounds.half_area();
        const float leaf_cost = settings_.build.intersection_cost * area * float(c.info.weight);
        const float split_cost = settings_.build.traversal_cost * area +
                                 settings_.build.intersection_cost * c.split.cost;
        c.is_leaf = n <= settings_.build.max_leaf_size && leaf_cost <= split_cost;
        return c;
    }

    /// Step (3)-(4): partition, share the free space (§5.2), prepare both children.
    std::array<RebraidCandidate, 2> split(const RebraidCandidate& c, bool median_only) const {
        const BRefSegment& segment = c.segment;
        const std::size_t threshold = settings_.build.parallel_threshold;
        std::uint32_t mid = segment.start + segment.size() / 2;
        if (c.split.is_valid())
            mid = segment.start +
                  std::uint32_t(parallel_partition(
                      range(segment), [&](const BuildPrim& p) { return c.split.goes_left(p); },
                      threshold));
        const RangeInfo left_info =
            compute_range_info(prims_.subspan(segment.start, mid - segment.start), threshold);
        const RangeInfo right_info =
            compute_range_info(prims_.subspan(mid, segment.end - mid), threshold);
        BRefSegment left{segment.start, mid, mid, segment.next_target, segment.can_open};
        BRefSegment right{mid, segment.end, segment.end, segment.next_target, segment.can_open};
        if (segment.can_open && segment.free_space() > 0) {
            const std::uint32_t left_openable =
                count_openable(prims_.subspan(segment.start, mid - segment.start), targets_,
                               criterion_for(left_info.bounds), threshold);
            const std::uint32_t right_openable =
                count_openable(prims_.subspan(mid, segment.end - mid), targets_,
                               criterion_for(right_info.bounds), threshold);
            std::tie(left, right) =
                split_free_space(segment, mid, left_openable, right_openable, prims_);
        }
        return {prepare(left, median_only, left_info), prepare(right, median_only, right_info)};
    }

    NodeRef make_leaf(const RebraidCandidate& c) const {
        return NodeRef::leaf(c.segment.start, c.segment.size());
    }

    std::uint64_t opened() const { return opened_; }

private:
    OpeningCriterion criterion_for(const BBox3f& bounds) const {
        return OpeningCriterion(bounds, settings_.open_threshold, settings_.open_leaves);
    }

    /// Step (2): opens the BRefs the settings' rule picks (§4.2, §5.3, or issue 10's
    /// overlap and SAH-aware rules); returns how many.
    std::uint32_t open_segment(BRefSegment& segment, const BBox3f& bounds) const {
        const std::size_t threshold = settings_.build.parallel_threshold;
        OpeningCriterion criterion = criterion_for(bounds);
        std::vector<std::uint8_t> overlapping;
        if (settings_.opening_rule == OpeningRule::overlap) {
            overlapping =
                select_overlapping(range(segment), targets_, bounds, settings_.overlap_threshold);
            criterion.selected = overlapping;
        }
        if (settings_.opening_rule != OpeningRule::extent &&
            !estimate_opening(range(segment), targets_, criterion, source_, segment.free_space(),
                              settings_)
                 .lowers_sah())
            return 0;  // the subtree below may still open: its segments are smaller
        return open_brefs(segment, prims_, targets_, criterion, source_, threshold);
    }

    std::span<BuildPrim> range(const BRefSegment& s) const {
        return prims_.subspan(s.start, s.size());
    }

    std::span<BuildPrim> prims_;
    std::span<BRefTarget> targets_;
    const BRefSource& source_;
    const RebraidSettings& settings_;
    // A statistic only: the sum is the same whatever order the tasks add in.
    mutable std::atomic<std::uint64_t> opened_{0};
};

/// Leaves reference the BRef array with its unused free space in between; renumber them into
/// a dense item list (in array order) and fill the top level's items.
/// `item_slots` receives each item's target slot.
void emit_items(TopLevelBvh& top, std::span<const BuildPrim> prims,
                std::span<const BRefTarget> targets, std::vector<std::uint32_t>& item_slots) {
    std::vector<std::uint32_t> dense(prims.size() + 1, 0);
    std::vector<char> used(prims.size(), 0);
    auto mark = [&](NodeRef ref) {
        for (std::uint32_t i = 0; i < ref.prim_count(); ++i) used[ref.first_prim() + i] = 1;
    };
    if (top.root.is_leaf()) mark(top.root);
    for (const WideNode& node : top.nodes)
        for (NodeRef ref : node.children)
            if (ref.is_leaf()) mark(ref);
    for (std::size_t i = 0; i < prims.size(); ++i) dense[i + 1] = dense[i] + used[i];
    top.items.resize(dense.back());
    top.item_bounds.resize(dense.back());
    item_slots.resize(dense.back());
    for (std::size_t i = 0; i < prims.size(); ++i) {
        if (!used[i]) continue;
        item_slots[dense[i]] = prims[i].id;
        top.items[dense[i]] = targets[prims[i].id];
        top.item_bounds[dense[i]] = prims[i].bounds;
    }
    auto renumber = [&](NodeRef ref) {
        return NodeRef::leaf(dense[ref.first_prim()], ref.prim_count());
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
};

TrackedBuild build_rebraid_once(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                                const RebraidSettings& settings,
                                std::span<const InstanceId> instances, bool is_tracking_cost);

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
    const BuildTimer timer;
    const bool is_guarded =
        settings.opening_rule != OpeningRule::extent && settings.keep_cheaper_unopened;
    TrackedBuild result = build_rebraid_once(scene, object_bvhs, settings, instances, is_guarded);
    if (is_guarded && result.build.opened > 0) {
        // The opening rules estimate; the guard measures: the same instances without any
        // opening, kept when its exact cost is not higher.
        RebraidSettings unopened = settings;
        unopened.opening_rule = OpeningRule::extent;
        unopened.budget_rule = BudgetRule::per_instance;
        unopened.budget_factor = 0.0f;
        TrackedBuild plain = build_rebraid_once(scene, object_bvhs, unopened, instances, true);
        if (plain.cost <= result.cost) {
            plain.build.budget = result.build.budget;
            result = std::move(plain);
        }
    }
    result.build.top.build_ms = timer.elapsed_ms();
    return std::move(result.build);
}

namespace {

TrackedBuild build_rebraid_once(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                                const RebraidSettings& settings,
                                std::span<const InstanceId> instances, bool is_tracking_cost) {
    if (object_bvhs.size() != scene.meshes.size())
        throw Error("build_rebraid: " + std::to_string(object_bvhs.size()) + " object BVHs for " +
                    std::to_string(scene.meshes.size()) + " meshes");
    std::vector<std::uint32_t> instance_mesh(scene.instances.size());
    std::vector<AffineTransform> object_to_world(scene.instances.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        instance_mesh[i] = scene.instances[i].mesh_id;
        object_to_world[i] = scene.instances[i].object_to_world;
    }
    std::uint64_t seed_count = 0, primitive_count = 0;
    for (const InstanceId i : instances) {
        if (i >= scene.instances.size())
            throw Error("build_rebraid: instance " + std::to_string(i) + " of a scene with " +
                        std::to_string(scene.instances.size()) + " instances");
        const ObjectBvh& bvh = object_bvhs[instance_mesh[i]];
        if (bvh.root.is_empty()) continue;
        ++seed_count;
        primitive_count += bvh.prim_count();
    }

    // §5.2: one array for every BRef the build can ever hold, allocated once.
    RebraidBuild result;
    const std::uint64_t limit = NodeRef::kMaxFirst;
    if (seed_count > limit)
        throw Error("build_rebraid: " + std::to_string(seed_count) +
                    " instances exceed the limit of " + std::to_string(limit));
    result.budget =
        std::min(bref_budget(settings, seed_count, primitive_count), limit - seed_count);
    const auto capacity = std::uint32_t(seed_count + result.budget);
    std::vector<BuildPrim> prims(capacity);
    std::vector<BRefTarget> targets(capacity);
    std::vector<double> node_cost(is_tracking_cost ? capacity : 0);
    std::vector<double> removed_cost(is_tracking_cost ? capacity : 0);
    std::uint32_t n = 0;
    for (const InstanceId i : instances) {
        const ObjectBvh& bvh = object_bvhs[instance_mesh[i]];
        if (bvh.root.is_empty()) continue;
        // One BRef per instance at its object root, with the root's primitive count (§3.2).
        prims[n] = {
            bref_world_bounds(bvh, bvh.root, bvh.bounds, object_to_world[i], settings.bounds_rule),
            n, bvh.prim_count()};
        targets[n] = {InstanceId(i), bvh.root};
        if (is_tracking_cost)
            node_cost[n] = mapped_box_half_area(bvh.bounds, object_to_world[i]) *
                           (bvh.root.is_leaf() ? bvh.root.prim_count() : 1.0);
        ++n;
    }

    // The paper's rule estimates child counts (§5.3); the others use the real ones.
    std::vector<std::vector<std::uint32_t>> subtree_prims;
    if (settings.opening_rule != OpeningRule::extent)
        subtree_prims = subtree_prim_counts(scene, object_bvhs, instances);
    const BRefSource source{
        object_bvhs,   instance_mesh,        object_to_world, settings.bounds_rule,
        subtree_prims, settings.open_leaves, node_cost,       removed_cost};
    const RebraidPolicy policy(prims, targets, source, settings);
    const RebraidCandidate root = policy.prepare(BRefSegment{0, n, capacity, n, true}, false);
    TopLevelBvh& top = result.top;
    top.bounds = root.info.bounds;
    if (n > 0)
        top.root = root.is_leaf ? policy.make_leaf(root)
                                : grow_wide_subtree(policy, root, 0,
                                                    settings.build.parallel_threshold, top.nodes);
    std::vector<std::uint32_t> item_slots;
    emit_items(top, prims, targets, item_slots);
    result.brefs = top.items.size();
    result.opened = policy.opened();
    TrackedBuild tracked{std::move(result), 0.0};
    if (is_tracking_cost)
        tracked.cost = cost_above_objects(tracked.build.top, item_slots, node_cost, removed_cost);
    return tracked;
}

}  // namespace

InstancedAccel build_rebraid_accel(const Scene& scene, const ObjectBvhBuilder& object_builder,
                                   const RebraidSettings& settings) {
    scene.validate();
    settings.validate();
    const BuildTimer timer;
    std::vector<ObjectBvh> object_bvhs = build_object_bvhs(scene, object_builder);
    RebraidBuild build = build_rebraid(scene, object_bvhs, settings);
    AccelStats info;
    info.build_ms = timer.elapsed_ms();
    info.top_build_ms = build.top.build_ms;
    info.brefs = build.brefs;
    info.budget = build.budget;
    info.opened = build.opened;
    return InstancedAccel(scene, std::move(object_bvhs), std::move(build.top), info);
}

}  // namespace rebraid
