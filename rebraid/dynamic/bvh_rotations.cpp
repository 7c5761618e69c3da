#include "rebraid/dynamic/bvh_rotations.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <utility>

#include "rebraid/core/error.h"
#include "rebraid/dynamic/object_bvh_refit.h"

namespace rebraid {
namespace {

/// What the pass returns for a subtree: its box, cost and height. Kept small (it is
/// returned for every leaf and node); the moves are counted in a RotationPassStats passed
/// down instead.
struct SubtreePass {
    BBox3f bounds;
    double cost = 0.0;
    int height = 0;  ///< inner levels: 0 for a leaf
};

void add_moves(RotationPassStats& total, const RotationPassStats& part) {
    total.swaps += part.swaps;
    total.pull_ups += part.pull_ups;
    total.exchanges += part.exchanges;
    total.splits += part.splits;
    total.merges += part.merges;
}

/// Boxes of up to kBvhWidth children plane by plane, so the loops over slots vectorise.
struct SlotBoxes {
    std::array<float, kBvhWidth> lower_x, lower_y, lower_z, upper_x, upper_y, upper_z;
};

/// Box `slot` of `boxes`.
inline BBox3f slot_box(const SlotBoxes& boxes, int slot) {
    return {{boxes.lower_x[slot], boxes.lower_y[slot], boxes.lower_z[slot]},
            {boxes.upper_x[slot], boxes.upper_y[slot], boxes.upper_z[slot]}};
}

inline void set_slot_box(SlotBoxes& boxes, int slot, const BBox3f& box) {
    boxes.lower_x[slot] = box.min.x, boxes.lower_y[slot] = box.min.y;
    boxes.lower_z[slot] = box.min.z, boxes.upper_x[slot] = box.max.x;
    boxes.upper_y[slot] = box.max.y, boxes.upper_z[slot] = box.max.z;
}

/// Half areas of (box `slot` of `boxes` merged with `extra`) for every slot.
inline void merged_half_areas(const SlotBoxes& boxes, const BBox3f& extra,
                              float (&areas)[kBvhWidth]) {
    for (int m = 0; m < kBvhWidth; ++m) {
        const float dx =
            std::max(boxes.upper_x[m], extra.max.x) - std::min(boxes.lower_x[m], extra.min.x);
        const float dy =
            std::max(boxes.upper_y[m], extra.max.y) - std::min(boxes.lower_y[m], extra.min.y);
        const float dz =
            std::max(boxes.upper_z[m], extra.max.z) - std::min(boxes.lower_z[m], extra.min.z);
        areas[m] = dx * dy + dy * dz + dz * dx;
    }
}

/// Summed half areas of the first `child_count` child boxes of `node`.
float child_area_sum(const WideNode& node, int child_count) {
    float sum = 0.0f;
    for (int slot = 0; slot < child_count; ++slot) sum += node.child_bounds(slot).half_area();
    return sum;
}

/// The best move found at a node.
struct Move {
    enum class Kind { none, swap, pull_up, exchange } kind = Kind::none;
    float gain = 0.0f;         ///< SAH decrease (half-area units)
    int child = 0;             ///< slot in N of the inner child G
    int grandchild = 0;        ///< slot in G of the grandchild g
    int other = 0;             ///< swap: slot in N of the child C that trades places with g;
                               ///< exchange: slot in N of the other inner child G2
    int other_grandchild = 0;  ///< exchange: slot in G2 of the grandchild g2 trading with g
};

/// What the move search needs of one inner child G of the node: its area, its children's
/// boxes, and for each slot m the half area of G's box without child m merged with any box.
/// Plain arrays without initialisers: the search runs at every node with inner children.
struct InnerChild {
    int slot;
    int count;
    float area;
    float most_shrink;  ///< largest area G loses by dropping one child: bounds any gain at G
    int outlier;        ///< the child whose dropping shrinks G most
    SlotBoxes boxes;    ///< G's children's boxes (slots past count unused)
    SlotBoxes without;  ///< G's box without child m, per m (empty past count)
    /// The intersection of the `without` boxes, per axis the second lowest lower bound to the
    /// second highest upper bound of G's children (possibly inverted). G without any one child
    /// contains it, so area(core + X) <= area(G without m + X) for every m: a lower bound on
    /// what G becomes when X replaces one of its children, computed once instead of per m.
    BBox3f core;
};

class RotationPass {
public:
    RotationPass(const Mesh& mesh, ObjectBvh& bvh, std::vector<std::uint8_t>& heights,
                 std::vector<float>& searched_areas, const RotationSettings& settings)
        : mesh_(mesh),
          bvh_(bvh),
          heights_(heights),
          searched_areas_(searched_areas),
          settings_(settings) {}

    /// Refits and rotates the subtree at inner node `ref`, counting moves into `moves`.
    SubtreePass run(NodeRef ref, int depth, RotationPassStats& moves) {
        const std::uint32_t node_id = ref.node_id();
        int child_count = bvh_.nodes[node_id].child_count();
        SubtreePass children[kBvhWidth];
        // Leaves inline (most children are leaves); inner children recurse, as parallel
        // tasks near the root, each task counting its moves apart (sums of counts do not
        // depend on the order they are added in).
        const auto run_child = [&](int slot, RotationPassStats& child_moves) {
            const NodeRef child = bvh_.nodes[node_id].children[slot];
            if (child.is_leaf()) {
                const BBox3f box = refit_leaf(mesh_, bvh_, child);
                children[slot] = {box, double(box.half_area()) * child.prim_count(), 0};
            } else {
                children[slot] = run(child, depth + 1, child_moves);
            }
        };
        if (depth < settings_.parallel_depth) {
            RotationPassStats child_moves[kBvhWidth];
            tbb::parallel_for(0, child_count,
                              [&](int slot) { run_child(slot, child_moves[slot]); });
            for (int slot = 0; slot < child_count; ++slot) add_moves(moves, child_moves[slot]);
        } else {
            for (int slot = 0; slot < child_count; ++slot) run_child(slot, moves);
        }
        WideNode& node = bvh_.nodes[node_id];
        SubtreePass result;
        // Slots a pull-up fills keep cost 0: the moved subtree's cost stays counted in the
        // slot it came from, its change in the move's gain.
        int heights[kBvhWidth] = {};
        double costs[kBvhWidth] = {};
        bool has_inner_child = false;
        for (int slot = 0; slot < child_count; ++slot) {
            node.set_child(slot, node.children[slot], children[slot].bounds);
            result.bounds.extend(children[slot].bounds);
            heights[slot] = children[slot].height;
            costs[slot] = children[slot].cost;
            has_inner_child = has_inner_child || heights[slot] > 0;
        }
        if (settings_.leaf_mode == RotationLeafMode::split_merge) {
            moves.merges += merge_leaf_nodes(node, child_count, heights, costs);
            moves.splits += split_leaves(node, child_count, heights, costs);
            has_inner_child = false;
            for (int slot = 0; slot < child_count; ++slot)
                has_inner_child = has_inner_child || heights[slot] > 0;
        }
        double cost_change = 0.0;
        // Moves need an inner child. Lazy search: only where the children grew since the
        // last search here (the change in area that Barbier and Paulin weight their treelet
        // sampling by).
        bool is_searched = has_inner_child && settings_.max_rotations_per_node > 0;
        if (is_searched && settings_.min_growth_to_search > 0.0f)
            is_searched = child_area_sum(node, child_count) >
                          searched_areas_[node_id] * (1.0f + settings_.min_growth_to_search);
        if (is_searched) {
            const float min_gain = settings_.min_relative_gain * result.bounds.half_area();
            for (int round = 0; round < settings_.max_rotations_per_node; ++round) {
                const Move move = best_move(node, child_count, heights, depth, min_gain);
                if (move.kind == Move::Kind::none) break;
                apply(node, child_count, heights, move);
                cost_change -= move.gain;
                ++(move.kind == Move::Kind::swap      ? moves.swaps
                   : move.kind == Move::Kind::pull_up ? moves.pull_ups
                                                      : moves.exchanges);
            }
            if (settings_.min_growth_to_search > 0.0f)
                searched_areas_[node_id] = child_area_sum(node, child_count);
        }
        result.cost = double(result.bounds.half_area()) + cost_change;
        for (int slot = 0; slot < child_count; ++slot) result.cost += costs[slot];
        result.height = 1 + *std::max_element(heights, heights + child_count);
        heights_[node_id] = std::uint8_t(result.height);
        return result;
    }

private:
    int height_of(NodeRef ref) const { return ref.is_inner() ? heights_[ref.node_id()] : 0; }

    /// Height of inner node `g` recomputed from its children.
    int recompute_height(const WideNode& g) const {
        int height = 0;
        for (int m = 0; m < kBvhWidth && !g.children[m].is_empty(); ++m)
            height = std::max(height, height_of(g.children[m]));
        return height + 1;
    }

    /// The move lowering the SAH most at `node` (gain above `min_gain`), respecting the depth
    /// limit, or Kind::none.
    Move best_move(const WideNode& node, int child_count, const int (&heights)[kBvhWidth],
                   int depth, float min_gain) const {
        Move best;
        best.gain = min_gain;
        InnerChild inner[kBvhWidth];
        int inner_count = 0;
        for (int i = 0; i < child_count; ++i) {
            if (!node.children[i].is_inner()) continue;
            InnerChild& g = inner[inner_count++];
            const WideNode& g_node = bvh_.nodes[node.children[i].node_id()];
            g.slot = i;
            g.count = g_node.child_count();
            g.area = node.child_bounds(i).half_area();
            // G's box without slot m, for every m: prefix and suffix unions.
            BBox3f prefix[kBvhWidth + 1], suffix[kBvhWidth + 1];
            for (int m = 0; m < g.count; ++m) {
                const BBox3f box = g_node.child_bounds(m);
                set_slot_box(g.boxes, m, box);
                prefix[m + 1] = merge(prefix[m], box);
            }
            for (int m = g.count; m > 0; --m)
                suffix[m - 1] = merge(suffix[m], slot_box(g.boxes, m - 1));
            for (int m = 0; m < kBvhWidth; ++m)
                set_slot_box(g.without, m,
                             m < g.count ? merge(prefix[m], suffix[m + 1]) : BBox3f{});
            g.most_shrink = -1.0f;
            constexpr float kInf = std::numeric_limits<float>::infinity();
            g.core = {{-kInf, -kInf, -kInf}, {kInf, kInf, kInf}};
            for (int m = 0; m < g.count; ++m) {
                const BBox3f without = merge(prefix[m], suffix[m + 1]);
                const float shrink = g.area - without.half_area();
                if (shrink > g.most_shrink) g.most_shrink = shrink, g.outlier = m;
                g.core = {max(g.core.min, without.min), min(g.core.max, without.max)};
            }
            // Adding a box never shrinks G, so no move at G gains more than most_shrink.
            if (g.most_shrink <= best.gain) continue;
            // Pull-up: g leaves G for a free slot of N. G keeps at least two children so it
            // stays a real node.
            if (child_count < kBvhWidth && g.count >= 3) {
                for (int m = 0; m < g.count; ++m) {
                    const float gain = g.area - merge(prefix[m], suffix[m + 1]).half_area();
                    if (gain > best.gain) best = {Move::Kind::pull_up, gain, i, m, 0, 0};
                }
            }
            // Swap: child C (slot j of N) and grandchild g (slot m of G) trade places.
            for (int j = 0; j < child_count; ++j) {
                if (j == i) continue;
                // No m can gain more than with G's core in place of G without m.
                if (g.area - merge(g.core, node.child_bounds(j)).half_area() <= best.gain) continue;
                float areas[kBvhWidth];
                merged_half_areas(g.without, node.child_bounds(j), areas);
                for (int m = 0; m < g.count; ++m) {
                    const float gain = g.area - areas[m];
                    if (gain <= best.gain) continue;
                    if (!swap_keeps_depth(node, child_count, heights, depth, i, m, j)) continue;
                    best = {Move::Kind::swap, gain, i, m, j, 0};
                }
            }
        }
        // Exchange: grandchildren g (under G) and g2 (under G2) trade places. Both G and G2
        // change, nothing else: the wide form of Kensler's grandchild/grandchild rotation,
        // and the move that trades triangles between sibling bottom nodes. An exchange gains
        // mostly by what leaves, so each side's outlier (the child whose leaving shrinks it
        // most) is tried against every child of the other side: 2 x 8 of the 64 pairs, at a
        // quarter of the cost.
        for (int a = 0; a < inner_count; ++a) {
            const InnerChild& g = inner[a];
            for (int b = a + 1; b < inner_count; ++b) {
                const InnerChild& g2 = inner[b];
                if (g.most_shrink + g2.most_shrink <= best.gain) continue;
                float g_areas[kBvhWidth], g2_areas[kBvhWidth];
                // g's outlier against each g2 child n: G = without outlier + n's box,
                // G2 = without n + outlier's box.
                // Each half is skipped when even G2's (G's) core taking the outlier leaves no
                // gain: the outlier usually lies far from the other side.
                const int m = g.outlier;
                const BBox3f m_box = slot_box(g.boxes, m);
                if (g.most_shrink + g2.area - merge(g2.core, m_box).half_area() > best.gain) {
                    merged_half_areas(g2.boxes, slot_box(g.without, m), g_areas);
                    merged_half_areas(g2.without, m_box, g2_areas);
                    for (int n = 0; n < g2.count; ++n)
                        consider_exchange(node, child_count, heights, depth, g, m, g2, n,
                                          g_areas[n], g2_areas[n], best);
                }
                // g2's outlier against each g child.
                const int n = g2.outlier;
                const BBox3f n_box = slot_box(g2.boxes, n);
                if (g2.most_shrink + g.area - merge(g.core, n_box).half_area() > best.gain) {
                    merged_half_areas(g.without, n_box, g_areas);
                    merged_half_areas(g.boxes, slot_box(g2.without, n), g2_areas);
                    for (int k = 0; k < g.count; ++k)
                        consider_exchange(node, child_count, heights, depth, g, k, g2, n,
                                          g_areas[k], g2_areas[k], best);
                }
            }
        }
        return best;
    }

    /// Takes the exchange of child `m` of `g` with child `n` of `g2`, whose new half areas
    /// are `g_area` and `g2_area`, as `best` when it gains more and keeps the depth limit.
    void consider_exchange(const WideNode& node, int child_count, const int (&heights)[kBvhWidth],
                           int depth, const InnerChild& g, int m, const InnerChild& g2, int n,
                           float g_area, float g2_area, Move& best) const {
        const float gain = (g.area - g_area) + (g2.area - g2_area);
        if (gain <= best.gain) return;
        if (!exchange_keeps_depth(node, child_count, heights, depth, g.slot, m, g2.slot, n)) return;
        best = {Move::Kind::exchange, gain, g.slot, m, g2.slot, n};
    }

    /// Height of inner node `g` if its child `m` were replaced by a subtree of `height`.
    int height_with(const WideNode& g, int m, int height) const {
        for (int k = 0; k < kBvhWidth && !g.children[k].is_empty(); ++k)
            if (k != m) height = std::max(height, height_of(g.children[k]));
        return height + 1;
    }

    /// True when exchanging grandchild `m` under child `i` with grandchild `n` under child
    /// `k` keeps the nesting below settings_.max_depth.
    bool exchange_keeps_depth(const WideNode& node, int child_count,
                              const int (&heights)[kBvhWidth], int depth, int i, int m, int k,
                              int n) const {
        const WideNode& g = bvh_.nodes[node.children[i].node_id()];
        const WideNode& g2 = bvh_.nodes[node.children[k].node_id()];
        int node_height = std::max(height_with(g, m, height_of(g2.children[n])),
                                   height_with(g2, n, height_of(g.children[m])));
        for (int slot = 0; slot < child_count; ++slot)
            if (slot != i && slot != k) node_height = std::max(node_height, heights[slot]);
        return depth + 1 + node_height <= settings_.max_depth;
    }

    /// True when swapping child `j` of `node` with grandchild `m` under child `i` keeps the
    /// nesting below settings_.max_depth.
    bool swap_keeps_depth(const WideNode& node, int child_count, const int (&heights)[kBvhWidth],
                          int depth, int i, int m, int j) const {
        const WideNode& g = bvh_.nodes[node.children[i].node_id()];
        int node_height = std::max(height_with(g, m, heights[j]), height_of(g.children[m]));
        for (int k = 0; k < child_count; ++k)
            if (k != i && k != j) node_height = std::max(node_height, heights[k]);
        return depth + 1 + node_height <= settings_.max_depth;
    }

    void apply(WideNode& node, int& child_count, int (&heights)[kBvhWidth], const Move& move) {
        const std::uint32_t g_id = node.children[move.child].node_id();
        WideNode& g = bvh_.nodes[g_id];
        const NodeRef moved = g.children[move.grandchild];
        const BBox3f moved_box = g.child_bounds(move.grandchild);
        if (move.kind == Move::Kind::exchange) {
            const std::uint32_t g2_id = node.children[move.other].node_id();
            WideNode& g2 = bvh_.nodes[g2_id];
            g.set_child(move.grandchild, g2.children[move.other_grandchild],
                        g2.child_bounds(move.other_grandchild));
            g2.set_child(move.other_grandchild, moved, moved_box);
            node.set_child(move.other, node.children[move.other], g2.bounds());
            heights_[g2_id] = std::uint8_t(recompute_height(g2));
            heights[move.other] = heights_[g2_id];
        } else if (move.kind == Move::Kind::swap) {
            g.set_child(move.grandchild, node.children[move.other], node.child_bounds(move.other));
            node.set_child(move.other, moved, moved_box);
            heights[move.other] = height_of(moved);
        } else {
            // Close the gap so used slots stay first.
            const int g_count = g.child_count();
            for (int m = move.grandchild; m + 1 < g_count; ++m)
                g.set_child(m, g.children[m + 1], g.child_bounds(m + 1));
            g.set_child(g_count - 1, NodeRef::empty(), BBox3f{});
            node.set_child(child_count, moved, moved_box);
            heights[child_count] = height_of(moved);
            ++child_count;
        }
        node.set_child(move.child, node.children[move.child], g.bounds());
        heights_[g_id] = std::uint8_t(recompute_height(g));
        heights[move.child] = heights_[g_id];
    }

    /// split_merge: collapses each inner child whose children are all leaves over one
    /// contiguous range of at most max_leaf_size triangles into a single leaf, when that
    /// lowers the SAH (it saves the node's own visit). The node is left unreferenced.
    std::uint64_t merge_leaf_nodes(WideNode& node, int child_count, int (&heights)[kBvhWidth],
                                   double (&costs)[kBvhWidth]) {
        std::uint64_t merges = 0;
        for (int slot = 0; slot < child_count; ++slot) {
            if (!node.children[slot].is_inner()) continue;
            const WideNode& g = bvh_.nodes[node.children[slot].node_id()];
            std::uint32_t first = NodeRef::kMaxFirst, end = 0, total = 0;
            bool all_leaves = true;
            for (int m = 0; m < kBvhWidth && !g.children[m].is_empty(); ++m) {
                const NodeRef leaf = g.children[m];
                if (!leaf.is_leaf()) {
                    all_leaves = false;
                    break;
                }
                first = std::min(first, leaf.first_prim());
                end = std::max(end, leaf.first_prim() + leaf.prim_count());
                total += leaf.prim_count();
            }
            // Disjoint ranges summing to the span of their union are one contiguous range.
            if (!all_leaves || total > settings_.max_leaf_size || end - first != total) continue;
            const BBox3f box = node.child_bounds(slot);
            const double merged_cost = double(box.half_area()) * total;
            if (merged_cost >= costs[slot]) continue;
            node.set_child(slot, NodeRef::leaf(first, total), box);
            costs[slot] = merged_cost;
            heights[slot] = 0;
            ++merges;
        }
        return merges;
    }

    /// split_merge: splits leaves of two or more triangles into two leaves while `node` has
    /// free slots, by the best SAH cut of their centroids along any axis, when that lowers the
    /// SAH. The triangles are reordered inside the leaf's own range.
    std::uint64_t split_leaves(WideNode& node, int& child_count, int (&heights)[kBvhWidth],
                               double (&costs)[kBvhWidth]) {
        std::uint64_t splits = 0;
        const int original_count = child_count;
        for (int slot = 0; slot < original_count && child_count < kBvhWidth; ++slot) {
            const NodeRef leaf = node.children[slot];
            if (!leaf.is_leaf() || leaf.prim_count() < 2) continue;
            const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
            const TriangleVerts* tris = bvh_.triangles.data() + first;
            BBox3f boxes[kMaxLeafSize];
            Vec3f centroids[kMaxLeafSize];
            for (std::uint32_t k = 0; k < count; ++k) {
                boxes[k] = {};
                boxes[k].extend(tris[k].v0), boxes[k].extend(tris[k].v1);
                boxes[k].extend(tris[k].v2);
                centroids[k] = boxes[k].center();
            }
            double best_cost = costs[slot];
            std::uint32_t best_order[kMaxLeafSize], best_left = 0;
            BBox3f best_left_box, best_right_box;
            for (int axis = 0; axis < 3; ++axis) {
                std::uint32_t order[kMaxLeafSize];
                for (std::uint32_t k = 0; k < count; ++k) order[k] = k;
                std::stable_sort(order, order + count, [&](std::uint32_t a, std::uint32_t b) {
                    return centroids[a][axis] < centroids[b][axis];
                });
                BBox3f suffix[kMaxLeafSize + 1];
                for (std::uint32_t k = count; k > 0; --k)
                    suffix[k - 1] = merge(suffix[k], boxes[order[k - 1]]);
                BBox3f prefix;
                for (std::uint32_t left = 1; left < count; ++left) {
                    prefix.extend(boxes[order[left - 1]]);
                    const double cost = double(prefix.half_area()) * left +
                                        double(suffix[left].half_area()) * (count - left);
                    if (cost >= best_cost) continue;
                    best_cost = cost;
                    best_left = left;
                    best_left_box = prefix;
                    best_right_box = suffix[left];
                    std::copy(order, order + count, best_order);
                }
            }
            if (best_left == 0) continue;
            // Reorder the leaf's range to the chosen cut's order.
            PrimId ids[kMaxLeafSize];
            TriangleVerts verts[kMaxLeafSize];
            for (std::uint32_t k = 0; k < count; ++k) {
                ids[k] = bvh_.prim_ids[first + best_order[k]];
                verts[k] = tris[best_order[k]];
            }
            std::copy(ids, ids + count, bvh_.prim_ids.begin() + first);
            std::copy(verts, verts + count, bvh_.triangles.begin() + first);
            node.set_child(slot, NodeRef::leaf(first, best_left), best_left_box);
            node.set_child(child_count, NodeRef::leaf(first + best_left, count - best_left),
                           best_right_box);
            costs[slot] = double(best_left_box.half_area()) * best_left;
            costs[child_count] = double(best_right_box.half_area()) * (count - best_left);
            heights[slot] = heights[child_count] = 0;
            ++child_count;
            ++splits;
        }
        return splits;
    }

    const Mesh& mesh_;
    ObjectBvh& bvh_;
    std::vector<std::uint8_t>& heights_;
    std::vector<float>& searched_areas_;
    const RotationSettings& settings_;
};

}  // namespace

void RotationSettings::validate() const {
    const auto fail = [](const std::string& what) { throw Error("RotationSettings: " + what); };
    if (max_leaf_size < 1 || max_leaf_size > kMaxLeafSize)
        fail("max_leaf_size " + std::to_string(max_leaf_size) + " is outside 1.." +
             std::to_string(kMaxLeafSize));
    if (max_rotations_per_node < 0)
        fail("max_rotations_per_node " + std::to_string(max_rotations_per_node) + " is negative");
    if (!(min_relative_gain >= 0.0f))
        fail("min_relative_gain " + std::to_string(min_relative_gain) + " is not >= 0");
    if (!(min_growth_to_search >= 0.0f))
        fail("min_growth_to_search " + std::to_string(min_growth_to_search) + " is not >= 0");
    if (max_depth < 1 || max_depth > kMaxBvhDepth)
        fail("max_depth " + std::to_string(max_depth) + " is outside 1.." +
             std::to_string(kMaxBvhDepth));
}

void BvhRotator::reset() {
    std::fill(searched_areas_.begin(), searched_areas_.end(), 0.0f);
}

RotationPassStats BvhRotator::refit_and_rotate(const Mesh& mesh, ObjectBvh& bvh,
                                               const RotationSettings& settings) {
    settings.validate();
    check_mesh_matches(mesh, bvh, "BvhRotator::refit_and_rotate");
    if (bvh.root.is_empty()) return {};
    // Heights of nodes are written before they are read (children first), so stale values
    // from an earlier tree do no harm.
    if (heights_.size() < bvh.nodes.size()) heights_.resize(bvh.nodes.size());
    if (searched_areas_.size() < bvh.nodes.size()) searched_areas_.resize(bvh.nodes.size(), 0.0f);
    RotationPassStats stats;
    if (bvh.root.is_leaf()) {
        bvh.bounds = refit_leaf(mesh, bvh, bvh.root);
        stats.sah = bvh.root.prim_count();
        return stats;
    }
    RotationPass pass(mesh, bvh, heights_, searched_areas_, settings);
    const SubtreePass root = pass.run(bvh.root, 0, stats);
    bvh.bounds = root.bounds;
    const double root_area = root.bounds.half_area();
    stats.sah = root_area > 0.0 ? root.cost / root_area : 0.0;
    bvh.refresh_leaf_rows();  // leaves may have been merged, split or reordered
    bvh.refresh_node_prim_counts();
    return stats;
}

}  // namespace rebraid
