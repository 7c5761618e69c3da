#include "rebraid/top_level/merged_top_level.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "rebraid/bvh/leaf_row_hints.h"
#include "rebraid/bvh/vertex_world_bounds.h"
#include "rebraid/core/huge_pages.h"

namespace rebraid {
namespace {

/// A top-level slot whose item is merged: the node and slot, and the item.
struct MergedSlot {
    std::uint32_t node = 0;
    int slot = 0;
    const TopLevelItem* item = nullptr;
};

/// The item a top-level leaf holds, when it can hang in the tree: one item naming an inner
/// object node.
const TopLevelItem* mergeable_item(const TopLevelBvh& top, NodeRef leaf) {
    if (!leaf.is_leaf() || leaf.prim_count() != 1) return nullptr;
    const TopLevelItem& item = top.items[leaf.first_prim()];
    return item.object_node.is_inner() ? &item : nullptr;
}

/// The item a top-level leaf holds, when its object leaf can hang in the top-level node in
/// its place: one item naming a whole object leaf (not part of one: rows are laid out per
/// whole leaf).
const TopLevelItem* hangable_item(const TopLevelBvh& top, NodeRef leaf) {
    if (top.has_partial_leaves || !leaf.is_leaf() || leaf.prim_count() != 1) return nullptr;
    const TopLevelItem& item = top.items[leaf.first_prim()];
    return item.object_node.is_leaf() && item.object_node.prim_count() > 0 ? &item : nullptr;
}

/// Inner nodes of `bvh` in the subtree below `start`.
std::uint32_t count_inner_nodes(const ObjectBvhView& bvh, NodeRef start) {
    std::uint32_t count = 0;
    std::vector<NodeRef> pending{start};
    while (!pending.empty()) {
        const NodeRef ref = pending.back();
        pending.pop_back();
        ++count;
        for (const NodeRef child : bvh.nodes[ref.node_id()].children)
            if (child.is_inner()) pending.push_back(child);
    }
    return count;
}

/// Copies the subtree below `start` of `bvh` into merged.nodes from id `first` on (in the
/// order a depth-first walk in slot order reaches its nodes), its nodes taking `source`.
void copy_subtree(MergedTopLevel& merged, const ObjectBvhView& bvh, std::uint32_t source,
                  NodeRef start, std::uint32_t first) {
    std::uint32_t next = first;
    const auto place = [&](NodeRef object_ref) {
        const std::uint32_t id = next++;
        merged.nodes[id] = bvh.nodes[object_ref.node_id()];
        return id;
    };
    // Copied nodes whose inner children still name object nodes.
    std::vector<std::uint32_t> pending{place(start)};
    while (!pending.empty()) {
        const std::uint32_t id = pending.back();
        pending.pop_back();
        WideNode& node = merged.nodes[id];
        const std::uint32_t source_word = MergedTopLevel::kSourceWordFlag | source;
        int fewest_lines_slot = 0;
        bool names_source = false;
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            NodeRef& child = node.children[slot];
            // Leaf and empty slots carry no hint: their words name the source.
            if (!child.is_inner()) {
                node.leaf_row_hints[slot] = source_word;
                names_source = true;
                continue;
            }
            if (leaf_row_hint_lines(node.leaf_row_hints[slot]) <=
                leaf_row_hint_lines(node.leaf_row_hints[fewest_lines_slot]))
                fewest_lines_slot = slot;
            const std::uint32_t copy = place(child);
            child = NodeRef::inner(copy);
            pending.push_back(copy);
        }
        if (!names_source) node.leaf_row_hints[fewest_lines_slot] = source_word;
    }
}

/// Gives the copied node `id` (copied from `bvh`, its instance placed by `to_world`) and
/// the copied nodes below it world-space boxes: per leaf child the box of its triangles'
/// corners mapped into the world, widened by 8 ulps of the mapping's terms as BRef boxes are
/// (the box test in world space and the triangle test in object space round differently),
/// per inner child the union of its children's; a leaf's box cut down to its mapped
/// object-space box, which alone holds no more than the parts of the triangles spatial splits
/// cut. Returns the node's box.
BBox3f fit_world_boxes(MergedTopLevel& merged, std::uint32_t id, const ObjectBvhView& bvh,
                       const AffineTransform& to_world) {
    BBox3f node_box;
    for (int slot = 0; slot < kBvhWidth; ++slot) {
        const NodeRef child = merged.nodes[id].children[slot];
        if (child.is_empty()) continue;
        BBox3f box;
        if (child.is_inner()) {
            box = fit_world_boxes(merged, child.node_id(), bvh, to_world);
        } else {
            float object_magnitude = 0.0f;
            for (std::uint32_t i = child.first_prim(); i < child.first_prim() + child.prim_count();
                 ++i)
                for (const Vec3f& corner :
                     {bvh.triangles[i].v0, bvh.triangles[i].v1, bvh.triangles[i].v2}) {
                    box.extend(to_world.transform_point(corner));
                    for (int axis = 0; axis < 3; ++axis)
                        object_magnitude = std::max(object_magnitude, std::fabs(corner[axis]));
                }
            box = intersection(
                widen_for_mapping_rounding(box, to_world, object_magnitude, 8.0f),
                to_world.transform_bbox_conservative(merged.nodes[id].child_bounds(slot)));
        }
        merged.nodes[id].set_child(slot, child, box);
        node_box.extend(box);
    }
    return node_box;
}

}  // namespace

MergedTopLevel merge_top_level_items(const TopLevelBvh& top,
                                     std::span<const InstanceTarget> targets,
                                     std::span<const ObjectBvhView> views,
                                     std::span<const AffineTransform> object_to_world,
                                     std::uint64_t object_nodes,
                                     const TopLevelMergeSettings& settings) {
    MergedTopLevel merged;
    if (!top.root.is_inner()) return merged;
    const auto is_world_space = [&](const TopLevelItem& item) {
        return targets[item.instance_id].space == InstanceTarget::kWorldSpace;
    };
    const auto bvh_of = [&](const TopLevelItem& item) -> const ObjectBvhView& {
        return views[targets[item.instance_id].mesh];
    };
    // Placed items' subtrees are copied only where all of them fit the budget. Their nodes
    // are counted first, and the count stops once the budget is spent (a scene of many
    // placed instances would otherwise walk every instanced node only to give up). The sum
    // only grows, so whether it ends over the budget does not depend on the order.
    bool merges_placed = false;
    if (settings.placed_instances) {
        std::vector<const TopLevelItem*> placed;
        for (const WideNode& node : top.nodes)
            for (const NodeRef child : node.children)
                if (const TopLevelItem* item = mergeable_item(top, child);
                    item && !is_world_space(*item))
                    placed.push_back(item);
        const double budget = double(settings.placed_node_budget) * double(object_nodes);
        std::atomic<std::uint64_t> copied{0};
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, placed.size()), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                if (double(copied.load(std::memory_order_relaxed)) > budget) return;
                copied.fetch_add(count_inner_nodes(bvh_of(*placed[i]), placed[i]->object_node),
                                 std::memory_order_relaxed);
            }
        });
        merges_placed = double(copied.load()) <= budget;
    }
    // World-space items are merged where most items are in world space, or where the placed
    // items are merged too. The merged loop costs every node a little more (the choice of
    // leaf visit, each object leaf's source), which the entries saved repay unless most items
    // still enter placed instances. Counting the world-space items that name object leaves
    // too (then entered, since hung) merged brainstem and cg57_cruiser, whose meshes placed
    // once are built in world space (meshes_in_world_space): 0.95 -> 1.03 and 0.92 -> 1.01
    // of Embree flat's speed on diffuse rays (docs/design.md, "World-space items merged into
    // the top level"). Where the placed items merge, a world-space item left alone is the one
    // entry left: two_cylinder_engine's engine block under the Embree glue's settings (0.33
    // of the root's area, entered by 0.14 of the primary rays; docs/design.md).
    const auto world_items = std::ranges::count_if(top.items, is_world_space);
    const bool merges_world_space =
        settings.world_space && (2 * std::size_t(world_items) >= top.items.size() || merges_placed);
    // Subtrees are copied as merges_subtree says; object leaves hang (copying nothing) as
    // hangs says: a placed instance's wherever placed items may merge.
    const auto merges_subtree = [&](const TopLevelItem& item) {
        return is_world_space(item) ? merges_world_space : merges_placed;
    };
    const auto hangs = [&](const TopLevelItem& item) {
        return is_world_space(item) ? merges_world_space : settings.placed_instances;
    };
    // Items naming inner object nodes: their subtrees are copied. Items naming object leaves:
    // the leaf itself hangs in the item's slot (no copy), tested with its node's other leaves
    // as a flat BVH's are, instead of entered.
    // The leaves hung in one node come from one instance (the first hangable slot's), so that
    // the traversal finds all of a node's object leaves in one source.
    std::vector<MergedSlot> slots, hung;
    for (std::uint32_t n = 0; n < top.nodes.size(); ++n) {
        const WideNode& node = top.nodes[n];
        const float node_area = node.bounds().half_area();
        InstanceId hung_instance = kInvalidId;
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef child = node.children[slot];
            if (const TopLevelItem* item = mergeable_item(top, child);
                item && merges_subtree(*item)) {
                slots.push_back({n, slot, item});
            } else if (const TopLevelItem* leaf_item = hangable_item(top, child);
                       leaf_item && hangs(*leaf_item) &&
                       node.child_bounds(slot).half_area() <=
                           MergedTopLevel::kHungLeafAreaShare * node_area) {
                if (hung_instance == kInvalidId) hung_instance = leaf_item->instance_id;
                if (leaf_item->instance_id == hung_instance) hung.push_back({n, slot, leaf_item});
            }
        }
    }
    if (slots.empty() && hung.empty()) return merged;

    // Each subtree's place in the copy, then the copies in parallel: sized once, as growing
    // the copy node by node moved and faulted it in again at every doubling (powerplant's
    // 109,000 object nodes took 200 ms that way).
    std::vector<std::uint32_t> first_node(slots.size() + 1);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots.size()), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            first_node[i + 1] =
                count_inner_nodes(bvh_of(*slots[i].item), slots[i].item->object_node);
    });
    // One source per hung leaf's instance, after the copied subtrees' (first use, in node and
    // slot order).
    std::vector<std::uint32_t> hung_source(targets.size(), kInvalidId);
    std::vector<InstanceId> hung_instances;
    for (const MergedSlot& slot : hung) {
        std::uint32_t& source = hung_source[slot.item->instance_id];
        if (source != kInvalidId) continue;
        source = std::uint32_t(slots.size() + hung_instances.size());
        hung_instances.push_back(slot.item->instance_id);
    }
    // A source's index sits below the flag and the hint's line count in a hint word.
    if (slots.size() + hung_instances.size() > NodeRef::kMaxFirst) return merged;
    first_node[0] = std::uint32_t(top.nodes.size());
    std::uint64_t node_count = first_node[0];
    for (std::size_t i = 0; i < slots.size(); ++i) {
        node_count += first_node[i + 1];
        // Inner references name nodes below NodeRef::kEmptyBits: a larger copy is not made
        // (the items are then entered as before).
        if (node_count >= NodeRef::kEmptyBits) return merged;
        first_node[i + 1] = std::uint32_t(node_count);
    }

    merged.first_object_node = std::uint32_t(top.nodes.size());
    reserve_on_huge_pages(merged.nodes, first_node.back());
    merged.nodes.assign(top.nodes.begin(), top.nodes.end());
    merged.nodes.resize(first_node.back());
    merged.sources.resize(slots.size() + hung_instances.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots.size()), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const MergedSlot& slot = slots[i];
            const ObjectBvhView& bvh = bvh_of(*slot.item);
            const InstanceTarget& target = targets[slot.item->instance_id];
            merged.sources[i] = {bvh.leaf_rows,          bvh.triangles, bvh.prim_ids,
                                 slot.item->instance_id, &target,       target.space};
            copy_subtree(merged, bvh, std::uint32_t(i), slot.item->object_node, first_node[i]);
            if (target.space != InstanceTarget::kWorldSpace)
                fit_world_boxes(merged, first_node[i], bvh,
                                object_to_world[slot.item->instance_id]);
            merged.nodes[slot.node].children[slot.slot] = NodeRef::inner(first_node[i]);
        }
    });
    for (std::size_t i = 0; i < hung_instances.size(); ++i) {
        const InstanceTarget& target = targets[hung_instances[i]];
        const ObjectBvhView& bvh = views[target.mesh];
        merged.sources[slots.size() + i] = {bvh.leaf_rows,     bvh.triangles, bvh.prim_ids,
                                            hung_instances[i], &target,       target.space};
    }
    for (const MergedSlot& slot : hung) {
        WideNode& node = merged.nodes[slot.node];
        node.children[slot.slot] = slot.item->object_node;
        node.leaf_row_hints[slot.slot] =
            MergedTopLevel::kSourceWordFlag | hung_source[slot.item->instance_id];
    }
    for (const MergedLeafSource& source : merged.sources)
        merged.every_source_has_rows = merged.every_source_has_rows && source.leaf_rows != nullptr;
    merged.root = top.root;
    // The items left: their areas' sum over the root's.
    double item_area = 0.0;
    for (std::uint32_t n = 0; n < merged.first_object_node; ++n)
        for (int slot = 0; slot < kBvhWidth; ++slot)
            if (MergedTopLevel::holds_item(merged.nodes[n], slot))
                item_area += double(merged.nodes[n].child_bounds(slot).half_area());
    merged.enters_items_out_of_line =
        item_area <= double(settings.items_out_of_line_area_share) *
                         merged.nodes[merged.root.node_id()].bounds().half_area();
    if (std::ranges::any_of(views, &ObjectBvhView::prefetches_rows))
        merged.rows_prefetch_from = merged.first_object_node;
    return merged;
}

}  // namespace rebraid
