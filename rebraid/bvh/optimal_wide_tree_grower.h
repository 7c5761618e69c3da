#pragma once

#include <tbb/task_group.h>

#include <array>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/huge_pages.h"

namespace rebraid {

/// The same top-down splits as WideTreeGrower (wide_tree_grower.h), cut into wide nodes by
/// cost rather than greedily: the binary tree of splits is built in full, and which of its
/// nodes become wide nodes is chosen to minimise the sum of their areas, the SAH's node cost,
/// under a limit of children per node (the dynamic programme of Ylitie, Karras and Laine,
/// "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, §3).
/// Leaves are the same either way, so their cost is left out. Filling each node by splitting
/// its largest child leaves small subtrees beside large ones, each a node of its own; the
/// cost-based cut has fewer nodes and a ray visits fewer (docs/design.md, "Leaves": used
/// for object and flat BVHs, not for top levels).
///
/// Same Policy and Candidate requirements as WideTreeGrower. Subtrees of at least
/// `task_threshold` primitives are built as TBB tasks; the result depends on the splits only,
/// never on the tasks. Nodes have at most `max_children` (2..kBvhWidth) children and are
/// numbered depth first, children in slot order.
template <class Policy, class Candidate>
class OptimalWideTreeGrower {
public:
    OptimalWideTreeGrower(const Policy& policy, std::size_t task_threshold,
                          std::uint32_t max_children = kBvhWidth)
        : policy_(policy), task_threshold_(task_threshold), slots_(int(max_children)) {}

    /// Fills `out` (cleared first) with the tree of `root`, which must not be a leaf; returns
    /// the root's reference.
    NodeRef grow(const Candidate& root, std::vector<WideNode>& out) const {
        Arenas arenas;
        std::deque<BinaryNode>& arena = arenas.add();
        BinaryNode& top = arena.emplace_back();
        build(root, 0, top, arenas, arena);
        out.clear();
        // On huge pages, as the greedy builders' node arrays: rays touch nodes all over it.
        reserve_on_huge_pages(out, node_count(top, slots_));
        emit(top, slots_, out);
        return NodeRef::inner(0);
    }

private:
    static constexpr int kSlots = kBvhWidth;

    /// The least node cost of a subtree in at most k slots of its parent, at [k - 1].
    using Costs = std::array<float, kSlots>;

    /// A node of the binary tree of splits, with how its subtree is best cut for each number
    /// of slots it may take in its parent (its costs go to the parent and are not kept: the
    /// binary tree lives until the cut is made, and is the build's largest extra memory).
    struct BinaryNode {
        BBox3f bounds;
        NodeRef leaf;  ///< for a leaf
        const BinaryNode* left = nullptr;
        const BinaryNode* right = nullptr;
        /// shape[k - 1]: 0 when the best form in at most k slots is one wide node, else the
        /// number of slots j (2..k) its children share.
        std::array<std::uint8_t, kSlots> shape{};
        /// left_slots[j - 1]: how many of j slots the left child takes in the best split.
        std::array<std::uint8_t, kSlots> left_slots{};
        bool is_leaf() const { return left == nullptr; }
    };

    /// Node storage of the build: one deque per task (stable addresses as it grows).
    class Arenas {
    public:
        std::deque<BinaryNode>& add() {
            const std::lock_guard lock(mutex_);
            arenas_.push_back(std::make_unique<std::deque<BinaryNode>>());
            return *arenas_.back();
        }

    private:
        std::mutex mutex_;
        std::vector<std::unique_ptr<std::deque<BinaryNode>>> arenas_;
    };

    /// Builds the subtree of `c` (not a leaf) into `node`; returns its costs.
    Costs build(const Candidate& c, std::uint32_t depth, BinaryNode& node, Arenas& arenas,
                std::deque<BinaryNode>& arena) const {
        node.bounds = c.bounds();
        // Median splits past the SAH depth limit bound the binary depth, and with it the
        // wide tree's (never deeper than the binary one), by kMaxBvhDepth.
        const bool median_only = depth + 1 >= std::uint32_t(kSahDepthLimit);
        std::array<Candidate, 2> halves = policy_.split(c, median_only);
        std::array<BinaryNode*, 2> kids{&arena.emplace_back(), &arena.emplace_back()};
        std::array<Costs, 2> kid_costs{};  // a leaf costs nothing in any number of slots
        std::optional<tbb::task_group> tasks;
        for (int h = 0; h < 2; ++h) {
            const Candidate& half = halves[h];
            BinaryNode& kid = *kids[h];
            if (half.is_leaf) {
                kid.bounds = half.bounds();
                kid.leaf = policy_.make_leaf(half);
            } else if (h == 0 && half.size() >= task_threshold_) {
                if (!tasks) tasks.emplace();
                tasks->run([this, &half, depth, &kid, &arenas, &costs = kid_costs[0]] {
                    costs = build(half, depth + 1, kid, arenas, arenas.add());
                });
            } else {
                kid_costs[h] = build(half, depth + 1, kid, arenas, arena);
            }
        }
        if (tasks) tasks->wait();
        node.left = kids[0];
        node.right = kids[1];
        return work_out_costs(node, c.area(), kid_costs[0], kid_costs[1], slots_);
    }

    /// The costs of `node` (of box area `area`) in each number of slots up to `slots`, from
    /// its children's, recording the best cut for each in `node`.
    static Costs work_out_costs(BinaryNode& node, float area, const Costs& left, const Costs& right,
                                int slots) {
        constexpr float kNone = std::numeric_limits<float>::infinity();
        // The children sharing j slots: each takes at least one.
        std::array<float, kSlots + 1> shared{};
        for (int j = 2; j <= slots; ++j) {
            shared[j] = kNone;
            for (int i = 1; i < j; ++i) {
                const float cost = left[i - 1] + right[j - i - 1];
                if (cost < shared[j]) {
                    shared[j] = cost;
                    node.left_slots[j - 1] = std::uint8_t(i);
                }
            }
        }
        Costs costs{};
        costs[0] = area + shared[slots];
        node.shape[0] = 0;
        for (int k = 2; k <= slots; ++k) {
            costs[k - 1] = costs[k - 2];
            node.shape[k - 1] = node.shape[k - 2];
            if (shared[k] < costs[k - 1]) {
                costs[k - 1] = shared[k];
                node.shape[k - 1] = std::uint8_t(k);
            }
        }
        return costs;
    }

    /// Appends the children `node` contributes in at most `slots` slots.
    static void gather(const BinaryNode& node, int slots,
                       std::array<const BinaryNode*, kSlots>& kids, int& count) {
        if (node.is_leaf() || node.shape[slots - 1] == 0) {
            kids[count++] = &node;
            return;
        }
        const int shared = node.shape[slots - 1];
        const int left = node.left_slots[shared - 1];
        gather(*node.left, left, kids, count);
        gather(*node.right, shared - left, kids, count);
    }

    /// The children of `node` as a wide node of at most `slots` children; returns their count.
    static int wide_children(const BinaryNode& node, int slots,
                             std::array<const BinaryNode*, kSlots>& kids) {
        int count = 0;
        const int left = node.left_slots[slots - 1];
        gather(*node.left, left, kids, count);
        gather(*node.right, slots - left, kids, count);
        return count;
    }

    /// The wide nodes emit() writes for `node`.
    static std::size_t node_count(const BinaryNode& node, int slots) {
        std::array<const BinaryNode*, kSlots> kids{};
        const int count = wide_children(node, slots, kids);
        std::size_t nodes = 1;
        for (int i = 0; i < count; ++i)
            if (!kids[i]->is_leaf()) nodes += node_count(*kids[i], slots);
        return nodes;
    }

    /// Writes `node` as a wide node of at most `slots` children at the end of `out`, then its
    /// inner children depth first; returns its id.
    static std::uint32_t emit(const BinaryNode& node, int slots, std::vector<WideNode>& out) {
        std::array<const BinaryNode*, kSlots> kids{};
        const int count = wide_children(node, slots, kids);
        const auto id = std::uint32_t(out.size());
        out.push_back(WideNode::make_empty());
        for (int i = 0; i < count; ++i) {
            const BinaryNode& kid = *kids[i];
            const NodeRef ref = kid.is_leaf() ? kid.leaf : NodeRef::inner(emit(kid, slots, out));
            // After the recursion: it may have grown (and moved) `out`.
            out[id].set_child(i, ref, kid.bounds);
        }
        return id;
    }

    const Policy& policy_;
    std::size_t task_threshold_;
    int slots_;
};

}  // namespace rebraid
