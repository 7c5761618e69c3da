#include "rebraid/rebraiding/sah_aware_opening.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <vector>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/build_box.h"
#include "rebraid/top_level/bvh_stats.h"

namespace rebraid {
namespace {

constexpr double kChildrenPerNode = kBvhWidth - 1;

/// Estimates over at least this many boxes run their independent parts as parallel tasks
/// (the virtual builds with and without opening, and the groups below the first level):
/// at the top of the tree they are the rule's longest serial stretches.
constexpr std::size_t kParallelEstimateBoxes = 256;

/// Candidates whose children's world boxes are still to be found are found in parallel from
/// this many on, this many per task: a BRef's children cost up to 48 searches of its object
/// BVH (vertex bounds), some microseconds.
constexpr std::size_t kParallelChildBoundsBRefs = 4;
constexpr std::size_t kChildBoundsBRefsPerTask = 2;

/// Half-area cost of the wide nodes a subtree over `count` boxes inside a box of half area
/// `area` needs, when nothing is known about how they shrink: (count - 1) / 7 nodes, each
/// as large as the box (an overestimate that grows with the count).
double unshrunk_cost(double area, std::size_t count) {
    return count <= 1 ? 0.0 : area * double(count - 1) / kChildrenPerNode;
}

/// How partition_measuring divided a range: boxes [0, left_count) went left.
struct MeasuredPartition {
    std::size_t left_count = 0;
    RangeAccumulator left, right;
};

/// Moves the boxes `split` sends left to the front (in place, from both ends) and measures
/// both sides on the way: one pass instead of a partition and a pass per side. The estimate
/// reads only the sides' sets, so their order inside does not matter.
MeasuredPartition partition_measuring(std::span<BuildPrim> boxes, const BinnedSplit& split) {
    MeasuredPartition result;
    std::size_t first = 0, last = boxes.size();
    while (true) {
        while (first != last && split.goes_left(boxes[first])) result.left.add(boxes[first++]);
        if (first == last) break;
        --last;
        while (first != last && !split.goes_left(boxes[last])) result.right.add(boxes[last--]);
        if (first == last) {
            result.right.add(boxes[first]);  // boxes[first] goes right: the loop above said so
            break;
        }
        std::swap(boxes[first], boxes[last]);
        result.left.add(boxes[first++]);
        result.right.add(boxes[last]);
    }
    result.left_count = first;
    return result;
}

/// Estimated half-area cost of the top-level nodes over `boxes` (weights 1; reordered): the
/// wide node over all of them, made as the builder makes it (binned SAH splits of its
/// largest child until it has kBvhWidth children), then `levels - 1` more wide levels the
/// same way, then unshrunk_cost below. `info` is compute_range_info of `boxes`, which the
/// caller has at hand (each group's comes from its split).
double estimate_top_cost(std::span<BuildPrim> boxes, const RangeInfo& info,
                         const BuildSettings& build, int levels) {
    if (boxes.size() <= 1) return 0.0;
    const double area = info.bounds.half_area();
    if (levels == 0) return unshrunk_cost(area, boxes.size());
    struct Group {
        std::span<BuildPrim> boxes;
        RangeInfo info;
        bool can_split = true;
    };
    // At most kBvhWidth groups: no allocation.
    std::array<Group, kBvhWidth> groups;
    std::size_t group_count = 1;
    groups[0] = {boxes, info, true};
    while (group_count < std::size_t(kBvhWidth)) {
        Group* largest = nullptr;
        for (std::size_t i = 0; i < group_count; ++i) {
            Group& g = groups[i];
            if (g.can_split && g.boxes.size() > 1 &&
                (!largest || g.info.bounds.half_area() > largest->info.bounds.half_area()))
                largest = &g;
        }
        if (!largest) break;
        const BinnedSplit split = find_binned_split(largest->boxes, largest->info, build);
        if (!split.is_valid()) {  // no plane separates the centroids
            largest->can_split = false;
            continue;
        }
        const MeasuredPartition parts = partition_measuring(largest->boxes, split);
        const std::span<BuildPrim> left = largest->boxes.first(parts.left_count);
        const std::span<BuildPrim> right = largest->boxes.subspan(parts.left_count);
        *largest = {left, parts.left.to_info(), true};
        groups[group_count++] = {right, parts.right.to_info(), true};
    }
    // The groups' costs in parallel for large ranges, summed in group order either way.
    std::array<double, kBvhWidth> group_costs{};
    auto group_cost = [&](std::size_t i) {
        const Group& g = groups[i];
        group_costs[i] = g.can_split ? estimate_top_cost(g.boxes, g.info, build, levels - 1)
                                     : unshrunk_cost(g.info.bounds.half_area(), g.boxes.size());
    };
    if (boxes.size() >= kParallelEstimateBoxes && levels > 1)
        tbb::parallel_for(std::size_t(0), group_count, group_cost);
    else
        for (std::size_t i = 0; i < group_count; ++i) group_cost(i);
    double cost = area;
    for (std::size_t i = 0; i < group_count; ++i) cost += group_costs[i];
    return cost;
}

/// Fills source.child_bounds for the BRefs of `to_open` to inner nodes, several BRefs per
/// task: each costs a search of its object BVH per child face, and the estimate would
/// otherwise make them one after the other. BRefs of instances whose transform takes boxes
/// to boxes need no search (bref_bounds.h) and are left to the estimate. Each BRef's slot is
/// its own, so the boxes are the same whichever task computes them.
void compute_child_bounds(std::span<const BuildPrim> prims, std::span<const BRefTarget> targets,
                          const BRefSource& source, std::span<const std::uint32_t> to_open) {
    if (!source.child_bounds || source.bounds_rule == BRefBoundsRule::transformed_box) return;
    std::vector<std::uint32_t> missing;  // indices into prims
    for (const std::uint32_t i : to_open) {
        const BRefTarget& target = targets[prims[i].id];
        if (target.object_node.is_inner() &&
            !source.object_to_world(target.instance_id).maps_boxes_to_boxes() &&
            !source.child_bounds->find(prims[i].id, target))
            missing.push_back(i);
    }
    if (missing.size() < kParallelChildBoundsBRefs) return;  // the estimate computes them
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, missing.size(), kChildBoundsBRefsPerTask),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t k = r.begin(); k < r.end(); ++k) {
                              const BuildPrim& prim = prims[missing[k]];
                              for_each_bref_child_bounds(
                                  source, prim.id, targets[prim.id],
                                  [](NodeRef, const BBox3f&, const BBox3f&) {});
                          }
                      });
}

}  // namespace

OpeningEstimate estimate_opening(std::span<const BuildPrim> prims, const RangeInfo& info,
                                 std::span<const BRefTarget> targets,
                                 const OpeningCriterion& criterion, const BRefSource& source,
                                 std::uint32_t free_space, const RebraidSettings& settings) {
    OpeningEstimate estimate;
    const double entry_cost = settings.instance_entry_cost;
    std::vector<BuildPrim> closed(prims.size()), opened;
    opened.reserve(prims.size() + free_space);
    double closed_items = 0.0, opened_items = 0.0;  // only the BRefs that would open
    RangeAccumulator opened_info;  // measured as the boxes go in: no pass of its own
    auto add_opened = [&](const BuildPrim& box) {
        opened.push_back(box);
        opened_info.add(box);
    };
    const std::vector<std::uint32_t> to_open =
        brefs_to_open(prims, targets, criterion, source, free_space);
    compute_child_bounds(prims, targets, source, to_open);
    estimate.opened = std::uint32_t(to_open.size());
    std::size_t next_open = 0;  // into to_open, which is in array order
    for (std::size_t i = 0; i < prims.size(); ++i) {
        const BuildPrim& prim = prims[i];
        closed[i] = {prim.bounds, 0, 1};
        if (next_open == to_open.size() || to_open[next_open] != i) {
            add_opened(closed[i]);
            continue;
        }
        ++next_open;
        const BRefTarget& target = targets[prim.id];
        const AffineTransform& to_world = source.object_to_world(target.instance_id);
        const NodeRef node = target.object_node;
        const double area = prim.bounds.half_area();
        closed_items += area * (node.is_leaf() ? node.prim_count() : 1.0) + entry_cost * area;
        for_each_bref_child_bounds(
            source, prim.id, target, [&](NodeRef child, const BBox3f& box, const BBox3f& bounds) {
                const double tests = child.is_leaf() ? child.prim_count() : 1.0;
                if (node.is_inner()) closed_items += mapped_box_half_area(box, to_world) * tests;
                const double child_area = bounds.half_area();
                opened_items += child_area * tests + entry_cost * child_area;
                add_opened({bounds, 0, 1});
            });
    }
    if (estimate.opened == 0) return estimate;
    const int levels = int(settings.estimate_levels);
    double closed_top = 0.0, opened_top = 0.0;
    // The closed boxes are the segment's own, each of weight 1.
    const RangeInfo closed_info{info.bounds, info.centroid_bounds, prims.size(),
                                std::uint32_t(prims.size())};
    auto estimate_closed = [&] {
        closed_top = estimate_top_cost(closed, closed_info, settings.build, levels);
    };
    auto estimate_opened = [&] {
        opened_top = estimate_top_cost(opened, opened_info.to_info(), settings.build, levels);
    };
    if (prims.size() >= kParallelEstimateBoxes) {
        tbb::parallel_invoke(estimate_closed, estimate_opened);
    } else {
        estimate_closed();
        estimate_opened();
    }
    estimate.closed_cost = closed_top + closed_items;
    estimate.opened_cost = opened_top + opened_items;
    return estimate;
}

}  // namespace rebraid
