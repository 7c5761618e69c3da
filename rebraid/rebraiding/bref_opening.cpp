#include "rebraid/rebraiding/bref_opening.h"

#include <algorithm>
#include <vector>

#include "rebraid/bvh/build_box.h"
#include "rebraid/core/parallel_blocks.h"
#include "rebraid/top_level/bvh_stats.h"

namespace rebraid {
namespace {

/// Children a BRef adds to the array when opened (its first child takes its own slot).
std::uint32_t extra_children(const BRefTarget& target, const BRefSource& source) {
    return bref_child_count(source, target) - 1;
}

}  // namespace

OpeningCriterion::OpeningCriterion(const BBox3f& segment_bounds, float open_threshold,
                                   bool open_leaves_too)
    : axis(segment_bounds.largest_axis()),
      min_extent(open_threshold * segment_bounds.extent()[segment_bounds.largest_axis()]),
      open_leaves(open_leaves_too) {}

OpeningScan scan_for_opening(std::span<const BuildPrim> prims, std::span<const BRefTarget> targets,
                             const OpeningCriterion& criterion, std::size_t parallel_threshold) {
    if (prims.empty()) return {};
    const InstanceId first_instance = targets[prims.front().id].instance_id;
    auto scan = [&](std::size_t begin, std::size_t end, OpeningScan result) {
        for (std::size_t i = begin; i != end; ++i) {
            const BRefTarget& target = targets[prims[i].id];
            result.openable += criterion.wants_to_open(prims[i], target, i);
            result.is_single_instance &= target.instance_id == first_instance;
        }
        return result;
    };
    // Integer sums and a logical and: the result does not depend on the blocks.
    return reduce_over_blocks(prims.size(), parallel_threshold, OpeningScan{}, scan,
                              [](OpeningScan a, const OpeningScan& b) {
                                  a.openable += b.openable;
                                  a.is_single_instance &= b.is_single_instance;
                                  return a;
                              });
}

namespace {

/// Opens the BRef `parent` (slot `parent_index` of the array) into its children (§5.3): the
/// first child replaces it, keeping its target slot; the `extra` siblings go to the free
/// space at `offset` past the segment's end, each with the next target slot.
void open_one(std::uint32_t parent_index, std::uint64_t offset, std::uint32_t extra,
              const BRefSegment& segment, std::span<BuildPrim> prims, std::span<BRefTarget> targets,
              const BRefSource& source) {
    BuildPrim& parent = prims[parent_index];
    const BRefTarget parent_target = targets[parent.id];
    const AffineTransform& to_world = source.object_to_world(parent_target.instance_id);
    const std::uint32_t estimated_weight = std::max(1u, parent.weight / (extra + 1));
    if (source.is_tracking_costs()) {
        // Slot parent.id only ever belongs to one segment at a time: no race.
        source.removed_cost[parent.id] += source.node_cost[parent.id];
    }
    std::uint32_t c = 0;
    const std::uint32_t parent_slot = parent.id;
    for_each_bref_child_bounds(
        source, parent_slot, parent_target,
        [&](NodeRef child, const BBox3f& box, const BBox3f& bounds) {
            const std::uint32_t weight =
                source.has_exact_counts()
                    ? std::max(1u, exact_prim_count(source, parent_target, child))
                    : estimated_weight;
            const BRefTarget child_target{parent_target.instance_id, child};
            const std::uint32_t child_slot =
                c == 0 ? parent.id : segment.next_target + std::uint32_t(offset + c - 1);
            if (source.is_tracking_costs())
                source.node_cost[child_slot] =
                    parent_target.object_node.is_leaf()
                        ? 0.0  // a triangle of an opened leaf: no object node of its own
                        : mapped_box_half_area(box, to_world) *
                              (child.is_leaf() ? child.prim_count() : 1.0);
            if (c == 0) {  // the first child replaces its parent, keeping its target slot
                parent = {bounds, parent.id, weight};
                targets[parent.id] = child_target;
            } else {
                prims[segment.end + std::uint32_t(offset + c - 1)] = {bounds, child_slot, weight};
                targets[child_slot] = child_target;
            }
            ++c;
        });
}

/// open_brefs for segments below the parallel threshold: one pass, a running offset (the
/// blocked version's prefix sums, computed as it goes), no allocation.
std::uint32_t open_brefs_serially(BRefSegment& segment, std::span<BuildPrim> prims,
                                  std::span<BRefTarget> targets, const OpeningCriterion& criterion,
                                  const BRefSource& source, RangeInfo* resulting_info) {
    const std::uint32_t first = segment.start, end = segment.end;
    const std::uint32_t space = segment.free_space();
    std::uint64_t offset = 0;
    std::uint32_t opened = 0;
    bool is_full = false;
    RangeAccumulator summary;
    for (std::uint32_t i = first; i < end; ++i) {
        if (!is_full) {
            const BRefTarget& target = targets[prims[i].id];
            if (criterion.wants_to_open(prims[i], target, i - first)) {
                const std::uint32_t extra = extra_children(target, source);
                if (offset + extra > space) {
                    is_full = true;  // this and every later BRef stay closed
                } else {
                    open_one(i, offset, extra, segment, prims, targets, source);
                    offset += extra;
                    ++opened;
                }
            }
        }
        if (resulting_info) summary.add(prims[i]);
    }
    if (resulting_info && opened > 0) {
        for (std::uint64_t k = 0; k < offset; ++k) summary.add(prims[end + k]);
        *resulting_info = summary.to_info();
    }
    segment.end += std::uint32_t(offset);
    segment.next_target += std::uint32_t(offset);
    return opened;
}

}  // namespace

std::uint32_t open_brefs(BRefSegment& segment, std::span<BuildPrim> prims,
                         std::span<BRefTarget> targets, const OpeningCriterion& criterion,
                         const BRefSource& source, std::size_t parallel_threshold,
                         RangeInfo* resulting_info) {
    const std::uint32_t first = segment.start, count = segment.size();
    if (count < parallel_threshold)
        return open_brefs_serially(segment, prims, targets, criterion, source, resulting_info);
    const std::uint32_t space = segment.free_space();
    const std::size_t block_count = parallel_block_count(count);

    // Pass 1: children wanted per block. Exclusive prefix sums give each block's first
    // output offset in the free space.
    std::vector<std::uint64_t> wanted(block_count + 1, 0);
    for_each_block(count, [&](std::size_t b, std::size_t begin, std::size_t end) {
        std::uint64_t sum = 0;
        for (std::uint32_t i = first + std::uint32_t(begin); i < first + end; ++i) {
            const BRefTarget& target = targets[prims[i].id];
            if (criterion.wants_to_open(prims[i], target, i - first))
                sum += extra_children(target, source);
        }
        wanted[b + 1] = sum;
    });
    for (std::size_t b = 0; b < block_count; ++b) wanted[b + 1] += wanted[b];

    // Pass 2: open while the inclusive prefix of wanted children fits the free space. Each
    // block records how far into the free space its last opening reached.
    std::vector<std::uint32_t> opened_in_block(block_count, 0);
    std::vector<std::uint64_t> reached(block_count, 0);
    for_each_block(count, [&](std::size_t b, std::size_t begin, std::size_t end) {
        std::uint64_t offset = wanted[b];
        for (std::uint32_t i = first + std::uint32_t(begin); i < first + end && offset <= space;
             ++i) {
            const BRefTarget& target = targets[prims[i].id];
            if (!criterion.wants_to_open(prims[i], target, i - first)) continue;
            const std::uint32_t extra = extra_children(target, source);
            if (offset + extra > space) break;  // this and every later BRef stay closed
            open_one(i, offset, extra, segment, prims, targets, source);
            offset += extra;
            reached[b] = offset;
            ++opened_in_block[b];
        }
    });

    // The opened BRefs are a prefix of the wanting ones, so their children fill the free
    // space contiguously up to the farthest point any block reached.
    std::uint64_t used = 0;
    std::uint32_t opened = 0;
    for (std::size_t b = 0; b < block_count; ++b) {
        opened += opened_in_block[b];
        used = std::max(used, reached[b]);
    }
    segment.end += std::uint32_t(used);
    segment.next_target += std::uint32_t(used);
    if (resulting_info && opened > 0)
        *resulting_info =
            compute_range_info(prims.subspan(first, segment.size()), parallel_threshold);
    return opened;
}

std::vector<std::uint32_t> brefs_to_open(std::span<const BuildPrim> prims,
                                         std::span<const BRefTarget> targets,
                                         const OpeningCriterion& criterion,
                                         const BRefSource& source, std::uint32_t free_space) {
    std::vector<std::uint32_t> chosen;
    std::uint64_t offset = 0;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        const BRefTarget& target = targets[prims[i].id];
        if (!criterion.wants_to_open(prims[i], target, i)) continue;
        const std::uint32_t extra = extra_children(target, source);
        if (offset + extra > free_space) break;
        offset += extra;
        chosen.push_back(std::uint32_t(i));
    }
    return chosen;
}

}  // namespace rebraid
