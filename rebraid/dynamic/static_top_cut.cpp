#include "rebraid/dynamic/static_top_cut.h"

#include <algorithm>
#include <queue>

#include "rebraid/bvh/object_subtree_counts.h"
#include "rebraid/core/error.h"

namespace rebraid {
namespace {

std::uint32_t height_below(const TopLevelBvh& top, NodeRef ref,
                           std::vector<std::uint32_t>& heights) {
    if (!ref.is_inner()) return 0;
    std::uint32_t deepest = 0;
    for (NodeRef child : top.nodes[ref.node_id()].children)
        deepest = std::max(deepest, height_below(top, child, heights));
    heights[ref.node_id()] = deepest + 1;
    return deepest + 1;
}

std::uint64_t prims_below(const TopLevelBvh& top, NodeRef ref, StaticTopSummary& summary) {
    if (ref.is_empty()) return 0;
    if (ref.is_leaf()) return summary.prims_of(ref);
    std::uint64_t sum = 0;
    for (NodeRef child : top.nodes[ref.node_id()].children) sum += prims_below(top, child, summary);
    summary.node_prims[ref.node_id()] = sum;
    return sum;
}

bool boxes_overlap(const BBox3f& a, const BBox3f& b) {
    return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y &&
           a.min.z <= b.max.z && b.min.z <= a.max.z;
}

/// True when `box` overlaps the box of some leaf of `tree`.
bool overlaps_some_leaf(const TopLevelBvh& tree, const BBox3f& box) {
    if (tree.root.is_empty() || !boxes_overlap(tree.bounds, box)) return false;
    if (tree.root.is_leaf()) return true;
    std::vector<std::uint32_t> stack{tree.root.node_id()};
    while (!stack.empty()) {
        const WideNode& node = tree.nodes[stack.back()];
        stack.pop_back();
        for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
            if (!boxes_overlap(node.child_bounds(slot), box)) continue;
            if (node.children[slot].is_leaf()) return true;
            stack.push_back(node.children[slot].node_id());
        }
    }
    return false;
}

}  // namespace

std::uint64_t StaticTopSummary::prims_of(NodeRef ref) const {
    if (ref.is_empty()) return 0;
    if (ref.is_inner()) return node_prims[ref.node_id()];
    std::uint64_t sum = 0;
    for (std::uint32_t i = 0; i < ref.prim_count(); ++i) sum += item_prims[ref.first_prim() + i];
    return sum;
}

StaticTopSummary summarize_static_top(const TopLevelBvh& top, const Scene& scene,
                                      std::span<const ObjectBvh> object_bvhs) {
    StaticTopSummary summary;
    // Node counts per mesh, made only for meshes some item enters below the root.
    const LazySubtreeCounts subtree_counts(object_bvhs);
    summary.item_prims.resize(top.items.size());
    for (std::size_t i = 0; i < top.items.size(); ++i) {
        const TopLevelItem& item = top.items[i];
        if (item.instance_id >= scene.instances.size())
            throw Error("summarize_static_top: item " + std::to_string(i) + " names instance " +
                        std::to_string(item.instance_id) + " of a scene with " +
                        std::to_string(scene.instances.size()));
        summary.item_prims[i] = subtree_counts.item_prim_count(
            scene.instances[item.instance_id].mesh_id, item.object_node);
    }
    summary.node_prims.assign(top.nodes.size(), 0);
    summary.node_height.assign(top.nodes.size(), 0);
    prims_below(top, top.root, summary);
    height_below(top, top.root, summary.node_height);
    return summary;
}

StaticTopCut cut_static_top(const TopLevelBvh& static_top, const TopLevelBvh& dynamic_top,
                            std::uint32_t max_piece_count) {
    StaticTopCut cut;
    if (static_top.root.is_empty()) return cut;
    std::vector<StaticTopPiece> reached{{static_top.root, static_top.bounds}};
    std::vector<char> is_kept{1};

    // Openable pieces, largest area first, then lowest node id: a strict order, so the cut is
    // the same whatever order they were found in.
    struct Openable {
        float area;
        std::uint32_t node_id;
        std::uint32_t piece;
        bool operator<(const Openable& other) const {
            return area != other.area ? area < other.area : node_id > other.node_id;
        }
    };
    std::priority_queue<Openable> openable;
    auto consider = [&](std::uint32_t piece) {
        const StaticTopPiece& p = reached[piece];
        if (p.ref.is_inner() && overlaps_some_leaf(dynamic_top, p.bounds))
            openable.push({p.bounds.half_area(), p.ref.node_id(), piece});
    };
    consider(0);
    std::uint32_t piece_count = 1;
    while (!openable.empty()) {
        const Openable next = openable.top();
        openable.pop();
        const WideNode& node = static_top.nodes[next.node_id];
        const auto child_count = std::uint32_t(node.child_count());
        if (piece_count - 1 + child_count > max_piece_count) continue;  // a smaller one may fit
        is_kept[next.piece] = 0;
        piece_count += child_count - 1;
        ++cut.opened_nodes;
        for (std::uint32_t slot = 0; slot < child_count; ++slot) {
            reached.push_back({node.children[slot], node.child_bounds(int(slot))});
            is_kept.push_back(1);
            consider(std::uint32_t(reached.size() - 1));
        }
    }
    cut.pieces.reserve(piece_count);
    for (std::size_t i = 0; i < reached.size(); ++i)
        if (is_kept[i]) cut.pieces.push_back(reached[i]);
    return cut;
}

}  // namespace rebraid
