#include "rebraid/dynamic/treelet_sampling.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "rebraid/bvh/grow_wide_subtree.h"
#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/dynamic/object_bvh_refit.h"

namespace rebraid {
namespace {

constexpr std::uint32_t kMaxTreeletLeaves = 64;
/// Cached area of a node id not weighed since the last reset.
constexpr float kUnseen = -1.0f;

/// A range of a treelet's subtrees while its inner nodes are rebuilt.
struct TreeletRange {
    std::uint32_t begin = 0, end = 0;
    BBox3f box;
    bool is_leaf = false;  ///< one subtree: it becomes a child reference as it is

    float area() const { return box.half_area(); }
    BBox3f bounds() const { return box; }
    std::size_t size() const { return end - begin; }
};

/// grow_wide_subtree's policy for rebuilding a treelet: binary splits by an exact SAH sweep
/// over the subtrees' centroids along each axis, each subtree weighing one. Its cost is what
/// the rebuild changes: the inner nodes above the subtrees, whose count grows with the number
/// of subtrees below them, not with their triangles. The subtrees are sorted along each axis
/// once (`order` holds three orders of `count` indices); a split keeps every range sorted by
/// partitioning the other two orders stably, so no split sorts again.
class TreeletPolicy {
public:
    TreeletPolicy(const std::vector<BBox3f>& boxes, std::vector<std::uint32_t>& order,
                  std::vector<std::uint8_t>& goes_left, std::vector<std::uint32_t>& scratch)
        : boxes_(boxes),
          count_(std::uint32_t(boxes.size())),
          order_(order),
          goes_left_(goes_left),
          scratch_(scratch) {
        order_.resize(3 * std::size_t(count_));
        goes_left_.resize(count_);
        scratch_.resize(count_);
        for (int axis = 0; axis < 3; ++axis) {
            std::uint32_t* items = axis_order(axis);
            for (std::uint32_t k = 0; k < count_; ++k) items[k] = k;
            std::sort(items, items + count_, [&](std::uint32_t a, std::uint32_t b) {
                const float ca = boxes_[a].min[axis] + boxes_[a].max[axis];
                const float cb = boxes_[b].min[axis] + boxes_[b].max[axis];
                return ca != cb ? ca < cb : a < b;
            });
        }
    }

    TreeletRange make_range(std::uint32_t begin, std::uint32_t end) const {
        TreeletRange range{begin, end, {}, end - begin == 1};
        const std::uint32_t* items = axis_order(0);
        for (std::uint32_t i = begin; i < end; ++i) range.box.extend(boxes_[items[i]]);
        return range;
    }

    std::array<TreeletRange, 2> split(const TreeletRange& range, bool median_only) const {
        const std::uint32_t count = range.end - range.begin;
        std::uint32_t best_left = count / 2;
        int best_axis = range.box.largest_axis();
        if (!median_only) {
            float best_cost = std::numeric_limits<float>::infinity();
            std::array<float, kMaxTreeletLeaves> right_areas;
            for (int axis = 0; axis < 3; ++axis) {
                const std::uint32_t* items = axis_order(axis) + range.begin;
                BBox3f right;
                for (std::uint32_t k = count; k > 1; --k) {
                    right.extend(boxes_[items[k - 1]]);
                    right_areas[k - 1] = right.half_area();
                }
                BBox3f left;
                for (std::uint32_t k = 1; k < count; ++k) {
                    left.extend(boxes_[items[k - 1]]);
                    const float cost =
                        left.half_area() * float(k) + right_areas[k] * float(count - k);
                    if (cost < best_cost) best_cost = cost, best_left = k, best_axis = axis;
                }
            }
        }
        // Both halves stay sorted along every axis (each order holds the range's subtrees, so
        // make_range and make_leaf may read any of them).
        const std::uint32_t* chosen = axis_order(best_axis) + range.begin;
        for (std::uint32_t k = 0; k < count; ++k) goes_left_[chosen[k]] = k < best_left;
        for (int axis = 0; axis < 3; ++axis) {
            if (axis == best_axis) continue;
            std::uint32_t* items = axis_order(axis) + range.begin;
            std::uint32_t left = 0, right = best_left;
            for (std::uint32_t k = 0; k < count; ++k)
                scratch_[goes_left_[items[k]] ? left++ : right++] = items[k];
            std::copy(scratch_.begin(), scratch_.begin() + count, items);
        }
        return {make_range(range.begin, range.begin + best_left),
                make_range(range.begin + best_left, range.end)};
    }

    NodeRef make_leaf(const TreeletRange& range) const {
        return NodeRef::leaf(axis_order(0)[range.begin], 1);
    }

private:
    std::uint32_t* axis_order(int axis) const { return order_.data() + axis * std::size_t(count_); }

    const std::vector<BBox3f>& boxes_;
    std::uint32_t count_;
    std::vector<std::uint32_t>& order_;
    std::vector<std::uint8_t>& goes_left_;
    std::vector<std::uint32_t>& scratch_;
};

/// Height (inner levels) of the local subtree at `local` of a rebuilt treelet, its subtrees
/// counting `subtree_height(ref)`.
template <class SubtreeHeight>
int built_height(const std::vector<WideNode>& built, std::uint32_t local,
                 const std::vector<NodeRef>& subtrees, const SubtreeHeight& subtree_height) {
    int height = 0;
    const WideNode& node = built[local];
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        const NodeRef child = node.children[slot];
        height = std::max(height, child.is_leaf() ? subtree_height(subtrees[child.first_prim()])
                                                  : built_height(built, child.node_id(), subtrees,
                                                                 subtree_height));
    }
    return height + 1;
}

float child_area_sum(const WideNode& node) {
    float sum = 0.0f;
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
        sum += node.child_bounds(slot).half_area();
    return sum;
}

}  // namespace

void TreeletSettings::validate() const {
    const auto fail = [](const std::string& what) { throw Error("TreeletSettings: " + what); };
    if (!(root_fraction > 0.0 && root_fraction <= 1.0))
        fail("root_fraction " + std::to_string(root_fraction) + " is outside (0, 1]");
    if (max_treelet_leaves < 2 || max_treelet_leaves > kMaxTreeletLeaves)
        fail("max_treelet_leaves " + std::to_string(max_treelet_leaves) + " is outside 2.." +
             std::to_string(kMaxTreeletLeaves));
    if (!(descendant_weight >= 0.0))
        fail("descendant_weight " + std::to_string(descendant_weight) + " is not >= 0");
    if (!(min_relative_gain >= 0.0f))
        fail("min_relative_gain " + std::to_string(min_relative_gain) + " is not >= 0");
}

void TreeletSampler::reset() {
    std::fill(cached_areas_.begin(), cached_areas_.end(), kUnseen);
    pass_count_ = 0;
}

void TreeletSampler::reset(const ObjectBvh& fresh) {
    cached_areas_.resize(fresh.nodes.size());
    for (std::size_t id = 0; id < fresh.nodes.size(); ++id)
        cached_areas_[id] = child_area_sum(fresh.nodes[id]);
    pass_count_ = 0;
}

double TreeletSampler::weigh(const ObjectBvh& bvh, std::uint32_t node_id, int depth, double alpha,
                             double& cost) {
    const WideNode& node = bvh.nodes[node_id];
    NodeInfo& info = info_[node_id];
    info = {};
    info.depth = std::uint16_t(depth);
    info.is_reachable = true;
    double below = 0.0;
    int height = 0;
    bool has_inner_child = false;
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        const NodeRef child = node.children[slot];
        const double area = node.child_bounds(slot).half_area();
        if (!child.is_inner()) {
            cost += area * child.prim_count();
            continue;
        }
        cost += area;
        has_inner_child = true;
        below += weigh(bvh, child.node_id(), depth + 1, alpha, cost);
        height = std::max(height, int(info_[child.node_id()].height));
    }
    // Growth since the node was last part of a drawn treelet (or first seen, for a node
    // never weighed: a fresh build has no damage yet).
    const float areas = child_area_sum(node);
    if (cached_areas_[node_id] < 0.0f) cached_areas_[node_id] = areas;
    const double growth = double(areas) - double(cached_areas_[node_id]);
    NodeInfo& updated = info_[node_id];  // weigh() of the children did not move info_
    updated.height = std::uint8_t(height + 1);
    // A node whose children are all leaves has nothing to restructure: it weighs only
    // through its parent.
    const double weight = std::max(0.0, growth + alpha * below);
    updated.weight = has_inner_child ? weight : 0.0;
    return weight;
}

double TreeletSampler::choose(const ObjectBvh& bvh, std::uint32_t node_id) {
    const WideNode& node = bvh.nodes[node_id];
    double skip = 0.0;
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
        if (node.children[slot].is_inner()) skip += choose(bvh, node.children[slot].node_id());
    NodeInfo& info = info_[node_id];
    info.best = skip;
    info.takes_treelet = false;
    if (info.treelet == 0) return skip;
    const Treelet& treelet = treelets_[info.treelet - 1];
    if (treelet.reward <= 0.0) return skip;
    // Subtrees of the treelet were visited above (they are descendants of its inner nodes).
    double take = treelet.reward;
    for (NodeRef subtree : treelet.subtrees)
        if (subtree.is_inner()) take += info_[subtree.node_id()].best;
    if (take > skip) info.best = take, info.takes_treelet = true;
    return info.best;
}

void TreeletSampler::collect_chosen(const ObjectBvh& bvh, std::uint32_t node_id,
                                    std::vector<std::uint32_t>& chosen) const {
    const NodeInfo& info = info_[node_id];
    if (info.best <= 0.0) return;  // no treelet below
    if (info.takes_treelet) {
        chosen.push_back(info.treelet - 1);
        for (NodeRef subtree : treelets_[info.treelet - 1].subtrees)
            if (subtree.is_inner()) collect_chosen(bvh, subtree.node_id(), chosen);
        return;
    }
    const WideNode& node = bvh.nodes[node_id];
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
        if (node.children[slot].is_inner())
            collect_chosen(bvh, node.children[slot].node_id(), chosen);
}

TreeletStats TreeletSampler::optimize(const Mesh& mesh, ObjectBvh& bvh,
                                      const TreeletSettings& settings) {
    settings.validate();
    check_mesh_matches(mesh, bvh, "TreeletSampler::optimize");
    TreeletStats stats;
    const double root_area = bvh.bounds.half_area();
    if (!bvh.root.is_inner() || root_area <= 0.0) {
        if (bvh.root.is_leaf()) stats.sah = bvh.root.prim_count();
        return stats;
    }

    // 1. Weights p(N), bottom up; unvisited ids are unreachable (free for reuse below).
    if (cached_areas_.size() < bvh.nodes.size()) cached_areas_.resize(bvh.nodes.size(), kUnseen);
    info_.assign(bvh.nodes.size(), NodeInfo{});
    const std::uint32_t root_id = bvh.root.node_id();
    double tree_cost = root_area;
    weigh(bvh, root_id, 0, settings.descendant_weight, tree_cost);

    // 2. Draw roots by weight: prefix sums over node ids, a seeded stream per pass.
    std::vector<double> prefix(bvh.nodes.size() + 1, 0.0);
    std::uint32_t inner_count = 0;
    for (std::uint32_t id = 0; id < bvh.nodes.size(); ++id) {
        prefix[id + 1] = prefix[id] + info_[id].weight;
        inner_count += info_[id].is_reachable;
    }
    const double total_weight = prefix.back();
    const auto draws = std::uint32_t(std::ceil(settings.root_fraction * inner_count));
    std::vector<std::uint32_t> roots;
    if (total_weight > 0.0) {
        Random random(settings.seed + pass_count_);
        for (std::uint32_t d = 0; d < draws; ++d) {
            const double target = total_weight * double(random.next_float01());
            const auto it = std::upper_bound(prefix.begin() + 1, prefix.end(), target);
            const auto id = std::uint32_t(std::min<std::ptrdiff_t>(
                it - prefix.begin() - 1, std::ptrdiff_t(bvh.nodes.size()) - 1));
            if (info_[id].weight > 0.0 && info_[id].treelet == 0) {
                roots.push_back(id);
                info_[id].treelet = 1;  // marked; numbered below in id order
            }
        }
    }
    ++pass_count_;
    std::sort(roots.begin(), roots.end());
    if (treelets_.size() < roots.size()) treelets_.resize(roots.size());
    for (std::uint32_t t = 0; t < roots.size(); ++t) info_[roots[t]].treelet = t + 1;
    stats.sampled = std::uint32_t(roots.size());

    // 3. Grow and rebuild each treelet, in parallel, reading the tree only.
    const auto height_of = [&](NodeRef ref) {
        return ref.is_inner() ? int(info_[ref.node_id()].height) : 0;
    };
    tbb::parallel_for(std::size_t(0), roots.size(), [&](std::size_t t) {
        Treelet& treelet = treelets_[t];
        treelet.root = roots[t];
        treelet.inner_ids.assign(1, roots[t]);
        treelet.subtrees.clear();
        treelet.subtree_boxes.clear();
        treelet.reward = 0.0;
        const WideNode& root = bvh.nodes[roots[t]];
        for (int slot = 0; slot < kBvhWidth && !root.children[slot].is_empty(); ++slot) {
            treelet.subtrees.push_back(root.children[slot]);
            treelet.subtree_boxes.push_back(root.child_bounds(slot));
        }
        // Open the largest inner subtree while the treelet stays within its size.
        double old_cost = 0.0;
        for (;;) {
            int pick = -1;
            float largest = -1.0f;
            for (std::size_t k = 0; k < treelet.subtrees.size(); ++k) {
                if (!treelet.subtrees[k].is_inner()) continue;
                const float area = treelet.subtree_boxes[k].half_area();
                if (area > largest) largest = area, pick = int(k);
            }
            if (pick < 0) break;
            const WideNode& opened = bvh.nodes[treelet.subtrees[pick].node_id()];
            const int count = opened.child_count();
            if (treelet.subtrees.size() - 1 + count > settings.max_treelet_leaves) break;
            treelet.inner_ids.push_back(treelet.subtrees[pick].node_id());
            old_cost += largest;
            treelet.subtrees[pick] = opened.children[0];
            treelet.subtree_boxes[pick] = opened.child_bounds(0);
            for (int slot = 1; slot < count; ++slot) {
                treelet.subtrees.push_back(opened.children[slot]);
                treelet.subtree_boxes.push_back(opened.child_bounds(slot));
            }
        }
        if (treelet.inner_ids.size() < 2) return;  // only the root: nothing to rearrange
        const auto count = std::uint32_t(treelet.subtrees.size());
        const TreeletPolicy policy(treelet.subtree_boxes, treelet.order, treelet.goes_left,
                                   treelet.scratch);
        treelet.built.clear();
        // Serial growth (a task threshold above any treelet): treelets are the parallel unit.
        grow_wide_subtree(policy, policy.make_range(0, count), info_[roots[t]].depth,
                          std::numeric_limits<std::size_t>::max(), treelet.built);
        double new_cost = 0.0;
        for (const WideNode& node : treelet.built)
            for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
                if (node.children[slot].is_inner()) new_cost += node.child_bounds(slot).half_area();
        const int old_height = info_[roots[t]].height;
        const int new_height = built_height(treelet.built, 0, treelet.subtrees, height_of);
        const double min_gain =
            settings.min_relative_gain * double(bvh.nodes[roots[t]].bounds().half_area());
        // Not deeper than before: then any set of applied treelets keeps every depth.
        if (new_height <= old_height && old_cost - new_cost > min_gain)
            treelet.reward = old_cost - new_cost;
    });
    // The drawn treelets' damage is dealt with (repaired below, or found not worth it):
    // their nodes start accumulating growth afresh.
    for (std::uint32_t t = 0; t < roots.size(); ++t) {
        stats.improved += treelets_[t].reward > 0.0;
        for (std::uint32_t id : treelets_[t].inner_ids)
            cached_areas_[id] = child_area_sum(bvh.nodes[id]);
    }

    // 4. The non-overlapping set of largest total reward.
    choose(bvh, root_id);
    std::vector<std::uint32_t> chosen;
    collect_chosen(bvh, root_id, chosen);

    // 5. Splice in choice order (top down), reusing the treelets' ids, then unreachable ids.
    std::vector<std::uint32_t> free_ids;
    for (std::uint32_t id = std::uint32_t(bvh.nodes.size()); id-- > 0;)
        if (!info_[id].is_reachable) free_ids.push_back(id);  // popped lowest first
    double cost_change = 0.0;
    std::vector<std::uint32_t> new_ids;
    for (std::uint32_t t : chosen) {
        Treelet& treelet = treelets_[t];
        new_ids.resize(treelet.built.size());
        for (std::size_t local = 0; local < treelet.built.size(); ++local) {
            if (local < treelet.inner_ids.size()) {
                new_ids[local] = treelet.inner_ids[local];
            } else if (!free_ids.empty()) {
                new_ids[local] = free_ids.back(), free_ids.pop_back();
            } else {
                new_ids[local] = std::uint32_t(bvh.nodes.size());
                bvh.nodes.push_back(WideNode::make_empty());
                cached_areas_.push_back(0.0f);
            }
        }
        for (std::size_t k = treelet.built.size(); k < treelet.inner_ids.size(); ++k)
            free_ids.push_back(treelet.inner_ids[k]);
        for (std::size_t local = 0; local < treelet.built.size(); ++local) {
            WideNode node = treelet.built[local];
            for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
                const NodeRef child = node.children[slot];
                if (child.is_inner()) {
                    node.children[slot] = NodeRef::inner(new_ids[child.node_id()]);
                } else {
                    const std::uint32_t k = child.first_prim();
                    node.set_child(slot, treelet.subtrees[k], treelet.subtree_boxes[k]);
                }
            }
            bvh.nodes[new_ids[local]] = node;
            cached_areas_[new_ids[local]] = child_area_sum(node);
        }
        cost_change -= treelet.reward;
        ++stats.applied;
        stats.nodes_rebuilt += treelet.inner_ids.size();
    }
    stats.sah = (tree_cost + cost_change) / root_area;
    if (stats.applied > 0) {  // treelets regroup the nodes (the leaves stay)
        bvh.refresh_node_prim_counts();
        bvh.refresh_leaf_row_hints();
    }
    return stats;
}

}  // namespace rebraid
