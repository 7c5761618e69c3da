#include "rebraid/dynamic/selective_restructuring.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/core/error.h"
#include "rebraid/dynamic/object_bvh_refit.h"

namespace rebraid {
namespace {

/// A rebuilt subtree waiting to be spliced in.
struct RebuiltSubtree {
    std::uint32_t node_id = 0;  ///< the old subtree's root, whose id the new root takes
    WideBvh tree;
    std::vector<BuildPrim> prims;  ///< leaf order of the new subtree; id = mesh primID
    /// Leaf-order positions the subtree's triangles occupy, ascending; empty when they are
    /// one contiguous range (then position i is the range's first + i).
    std::vector<std::uint32_t> positions;
    double cost = 0.0;  ///< SAH cost of the new subtree (half-area units)
    int height = 0;
};

/// SAH cost and height of the subtree at `ref` of a freshly built tree.
double built_cost(const WideBvh& tree, NodeRef ref, const BBox3f& box, int& height) {
    height = 0;
    if (ref.is_leaf()) return double(box.half_area()) * ref.prim_count();
    const WideNode& node = tree.nodes[ref.node_id()];
    double cost = box.half_area();
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        int child_height = 0;
        cost += built_cost(tree, node.children[slot], node.child_bounds(slot), child_height);
        height = std::max(height, child_height);
    }
    height += 1;
    return cost;
}

/// Leaf-order positions of the triangles below `ref`, in tree order.
void collect_positions(const ObjectBvh& bvh, NodeRef ref, std::vector<std::uint32_t>& positions) {
    if (ref.is_leaf()) {
        for (std::uint32_t i = 0; i < ref.prim_count(); ++i)
            positions.push_back(ref.first_prim() + i);
        return;
    }
    for (NodeRef child : bvh.nodes[ref.node_id()].children)
        if (!child.is_empty()) collect_positions(bvh, child, positions);
}

/// Inner node ids of the subtree at `ref`, below `ref` itself, depth first.
void collect_inner_below(const ObjectBvh& bvh, NodeRef ref, std::vector<std::uint32_t>& ids) {
    const WideNode& node = bvh.nodes[ref.node_id()];
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        if (!node.children[slot].is_inner()) continue;
        ids.push_back(node.children[slot].node_id());
        collect_inner_below(bvh, node.children[slot], ids);
    }
}

}  // namespace

void RestructureSettings::validate() const {
    const auto fail = [](const std::string& what) { throw Error("RestructureSettings: " + what); };
    if (!(max_rebuilt_fraction >= 0.0 && max_rebuilt_fraction <= 1.0))
        fail("max_rebuilt_fraction " + std::to_string(max_rebuilt_fraction) + " is outside [0, 1]");
    if (min_subtree_prims < 2)
        fail("min_subtree_prims " + std::to_string(min_subtree_prims) + " is below 2");
    if (!(min_relative_benefit >= 0.0))
        fail("min_relative_benefit " + std::to_string(min_relative_benefit) + " is not >= 0");
    build.validate();
}

double SelectiveRestructurer::measure(const ObjectBvh& bvh, NodeRef ref, const BBox3f& box,
                                      std::uint32_t parent, int depth) {
    const WideNode& node = bvh.nodes[ref.node_id()];
    NodeInfo info;
    info.parent = parent;
    info.depth = std::uint16_t(depth);
    info.is_reachable = true;
    info.first = NodeRef::kMaxFirst;
    info.cost = box.half_area();
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        const NodeRef child = node.children[slot];
        if (child.is_leaf()) {
            info.largest_leaf = std::max(info.largest_leaf, child.prim_count());
            info.cost += double(node.child_bounds(slot).half_area()) * child.prim_count();
            info.prim_count += child.prim_count();
            info.first = std::min(info.first, child.first_prim());
            info.end = std::max(info.end, child.first_prim() + child.prim_count());
        } else {
            info.cost += measure(bvh, child, node.child_bounds(slot), ref.node_id(), depth + 1);
            const NodeInfo& below = info_[child.node_id()];
            info.largest_leaf = std::max(info.largest_leaf, below.largest_leaf);
            info.prim_count += below.prim_count;
            info.first = std::min(info.first, below.first);
            info.end = std::max(info.end, below.end);
        }
    }
    info_[ref.node_id()] = info;
    return info.cost;
}

RestructureStats SelectiveRestructurer::restructure(const Mesh& mesh, ObjectBvh& bvh,
                                                    const RestructureSettings& settings) {
    settings.validate();
    check_mesh_matches(mesh, bvh, "SelectiveRestructurer::restructure");
    RestructureStats stats;
    const double root_area = bvh.bounds.half_area();
    if (!bvh.root.is_inner() || root_area <= 0.0) {
        if (bvh.root.is_leaf()) stats.sah = bvh.root.prim_count();
        return stats;
    }

    // 1. CM-IQ of every node (as SAH cost; CM-IQ = cost / half area).
    info_.assign(bvh.nodes.size(), NodeInfo{});
    const double tree_cost = measure(bvh, bvh.root, bvh.bounds, bvh.root.node_id(), 0);
    const double tree_sah = tree_cost / root_area;
    const auto cm_iq = [&](const WideNode& node, int slot) {
        const NodeRef child = node.children[slot];
        if (child.is_leaf()) return double(child.prim_count());
        const float area = node.child_bounds(slot).half_area();
        return area > 0.0f ? info_[child.node_id()].cost / area : 0.0;
    };

    // 2-3. RM-IQ benefit of each inner node, candidates scored by benefit per rebuild cost.
    candidates_.clear();
    const double min_benefit = settings.min_relative_benefit * tree_sah;
    for (std::uint32_t id = 0; id < bvh.nodes.size(); ++id) {
        const NodeInfo& info = info_[id];
        if (!info.is_reachable || info.prim_count < settings.min_subtree_prims) continue;
        // The rebuilt subtree must fit the old one's leaf-order positions: one contiguous
        // range takes any leaves, scattered single triangles (a pre-split tree after
        // rotations) take single-triangle leaves.
        const bool is_contiguous = info.end - info.first == info.prim_count;
        if (!is_contiguous && info.largest_leaf > 1) continue;
        const WideNode& node = bvh.nodes[id];
        const int count = node.child_count();
        double benefit = 0.0;
        for (int i = 0; i < count; ++i) {
            for (int j = i + 1; j < count; ++j) {
                const BBox3f overlap = intersection(node.child_bounds(i), node.child_bounds(j));
                if (overlap.is_empty()) continue;
                benefit += (cm_iq(node, i) + cm_iq(node, j)) * overlap.half_area();
            }
        }
        benefit /= root_area;
        if (benefit < min_benefit || benefit <= 0.0) continue;
        const double k = info.prim_count;
        candidates_.push_back({id, benefit / (k * std::log2(k))});
    }
    stats.candidates = std::uint32_t(candidates_.size());
    std::sort(candidates_.begin(), candidates_.end(), [](const Candidate& a, const Candidate& b) {
        return a.score != b.score ? a.score > b.score : a.node_id < b.node_id;
    });
    const auto budget = std::uint64_t(settings.max_rebuilt_fraction * double(bvh.prim_count()));
    std::uint64_t planned = 0;
    std::vector<RebuiltSubtree> rebuilt;
    for (const Candidate& candidate : candidates_) {
        NodeInfo& info = info_[candidate.node_id];
        if (info.is_taken || planned + info.prim_count > budget) continue;
        // Inside a chosen subtree? (Being an ancestor of one was checked by is_taken.)
        bool is_nested = false;
        for (std::uint32_t up = candidate.node_id;; up = info_[up].parent) {
            is_nested = is_nested || info_[up].is_chosen;
            if (is_nested || up == info_[up].parent) break;
        }
        if (is_nested) continue;
        info.is_chosen = true;
        for (std::uint32_t up = candidate.node_id;; up = info_[up].parent) {
            info_[up].is_taken = true;
            if (up == info_[up].parent) break;
        }
        planned += info.prim_count;
        rebuilt.emplace_back().node_id = candidate.node_id;
    }
    // 4. Rebuild the chosen subtrees in parallel, each over its own leaf-order range.
    tbb::parallel_for(std::size_t(0), rebuilt.size(), [&](std::size_t r) {
        RebuiltSubtree& subtree = rebuilt[r];
        const NodeInfo& info = info_[subtree.node_id];
        subtree.prims.resize(info.prim_count);
        if (info.end - info.first != info.prim_count) {
            collect_positions(bvh, NodeRef::inner(subtree.node_id), subtree.positions);
            std::sort(subtree.positions.begin(), subtree.positions.end());
        }
        const auto position = [&](std::uint32_t i) {
            return subtree.positions.empty() ? info.first + i : subtree.positions[i];
        };
        for (std::uint32_t i = 0; i < info.prim_count; ++i) {
            const TriangleVerts& tri = bvh.triangles[position(i)];
            BBox3f box;
            box.extend(tri.v0), box.extend(tri.v1), box.extend(tri.v2);
            subtree.prims[i] = {box, bvh.prim_ids[position(i)], 1};
        }
        // A subtree of single-triangle leaves stays one (rotations in pre_split mode rely on it).
        BuildSettings build = settings.build;
        if (info.largest_leaf == 1) build.max_leaf_size = 1;
        subtree.tree = build_wide_bvh(subtree.prims, build);
        subtree.cost =
            built_cost(subtree.tree, subtree.tree.root, subtree.tree.bounds, subtree.height);
    });

    // Splice serially, in choice order: node ids depend on nothing but that order.
    std::vector<std::uint32_t> free_ids;
    for (std::uint32_t id = std::uint32_t(bvh.nodes.size()); id-- > 0;)
        if (!info_[id].is_reachable) free_ids.push_back(id);  // popped lowest first
    double cost_change = 0.0;
    std::vector<std::uint32_t> reusable, new_ids;
    for (RebuiltSubtree& subtree : rebuilt) {
        const NodeInfo& info = info_[subtree.node_id];
        if (!subtree.tree.root.is_inner() || subtree.cost >= info.cost ||
            info.depth + subtree.height > kMaxBvhDepth)
            continue;
        reusable.clear();
        collect_inner_below(bvh, NodeRef::inner(subtree.node_id), reusable);
        std::reverse(reusable.begin(), reusable.end());  // popped in depth-first order
        const std::vector<WideNode>& built = subtree.tree.nodes;
        new_ids.assign(built.size(), 0);
        for (std::uint32_t local = 0; local < built.size(); ++local) {
            if (local == subtree.tree.root.node_id()) {
                new_ids[local] = subtree.node_id;
            } else if (!reusable.empty()) {
                new_ids[local] = reusable.back(), reusable.pop_back();
            } else if (!free_ids.empty()) {
                new_ids[local] = free_ids.back(), free_ids.pop_back();
            } else {
                new_ids[local] = std::uint32_t(bvh.nodes.size());
                bvh.nodes.push_back(WideNode::make_empty());
            }
        }
        free_ids.insert(free_ids.end(), reusable.rbegin(), reusable.rend());
        for (std::uint32_t local = 0; local < built.size(); ++local) {
            WideNode node = built[local];
            for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
                const NodeRef child = node.children[slot];
                if (!child.is_leaf())
                    node.children[slot] = NodeRef::inner(new_ids[child.node_id()]);
                else if (subtree.positions.empty())
                    node.children[slot] =
                        NodeRef::leaf(info.first + child.first_prim(), child.prim_count());
                else  // single-triangle leaves, see above
                    node.children[slot] = NodeRef::leaf(subtree.positions[child.first_prim()], 1);
            }
            bvh.nodes[new_ids[local]] = node;
        }
        for (std::uint32_t i = 0; i < info.prim_count; ++i) {
            const PrimId prim = subtree.prims[i].id;
            const auto corners = mesh.corners(prim);
            const std::uint32_t position =
                subtree.positions.empty() ? info.first + i : subtree.positions[i];
            bvh.prim_ids[position] = prim;
            bvh.triangles[position] = {corners[0], corners[1], corners[2]};
        }
        cost_change += subtree.cost - info.cost;
        ++stats.subtrees_rebuilt;
        stats.scattered_subtrees_rebuilt += !subtree.positions.empty();
        stats.prims_rebuilt += info.prim_count;
    }
    stats.sah = (tree_cost + cost_change) / root_area;
    if (stats.subtrees_rebuilt > 0) {  // rebuilt subtrees' leaves and nodes
        bvh.refresh_leaf_rows();
        bvh.refresh_node_prim_counts();
    }
    return stats;
}

}  // namespace rebraid
