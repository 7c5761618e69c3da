#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// How leaves are treated by refit_and_rotate(), the two variants of Kopta et al. 2012.
enum class RotationLeafMode {
    /// The tree has one triangle per leaf (built with max_leaf_size = 1) and leaves are never
    /// split or merged: rotations alone move triangles between subtrees (paper §2, §3.2, the
    /// variant the paper settles on).
    pre_split,
    /// Leaves hold several triangles; a leaf splits in two when its node has a free slot and
    /// the SAH falls, and a node whose children are all leaves collapses into one leaf when
    /// that lowers the SAH (the wide form of merging sibling leaves, paper §2, §3.1).
    split_merge,
};

/// Parameters of BvhRotator::refit_and_rotate(). The defaults are the `rotate` update
/// strategy's: leaves split and merged, up to two moves per node, nodes searched once their
/// children grew 1 %. On bench_update's twist (131k triangles, 100 frames, 1 thread) that
/// keeps the SAH within 1.144x of a per-frame rebuild at 1.6-1.7x the CPU time of a refit;
/// Kopta's schedule (pre_split, one move, every node every pass) reaches 1.205x at 2.8x
/// (./build/bench/bench_update).
struct RotationSettings {
    /// See RotationLeafMode. split_merge works on the builder's default trees (up to 4
    /// triangles per leaf), which trace faster than one-triangle-per-leaf trees and start
    /// with a lower SAH (a fresh pre-split tree has 1.095x the default's on twist).
    RotationLeafMode leaf_mode = RotationLeafMode::split_merge;
    /// split_merge: a collapse never makes a leaf with more triangles than this (1..16).
    std::uint32_t max_leaf_size = 4;
    /// Rotations applied per node and pass, each the best one at that node. Kopta applies
    /// one; more converge faster after sudden motion at a proportional search cost. With
    /// the lazy search below, two are cheaper overall than one: a node brought closer to
    /// its best shape in one pass needs searching in fewer later passes.
    int max_rotations_per_node = 2;
    /// A rotation must lower the SAH by more than this fraction of the node's half area:
    /// float noise must not make subtrees swap back and forth every frame.
    float min_relative_gain = 1e-5f;
    /// A node is searched for moves only when the summed half areas of its children grew by
    /// more than this fraction since its last search (0: every node every pass, as Kopta).
    /// Where the motion is slow, most nodes are then skipped at little loss of quality
    /// (twist: 1.144x instead of 1.132x a rebuild's SAH, at 0.65x the time).
    float min_growth_to_search = 0.01f;
    /// Wide levels whose children run as parallel tasks (as RefitSettings).
    int parallel_depth = 3;
    /// Deepest nesting of inner nodes a rotation may create; traversal stacks are sized
    /// for kMaxBvhDepth.
    int max_depth = kMaxBvhDepth;

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// What one refit-and-rotate pass did.
struct RotationPassStats {
    double sah = 0.0;             ///< SAH after the pass (as object_bvh_sah())
    std::uint64_t swaps = 0;      ///< child <-> grandchild swaps
    std::uint64_t pull_ups = 0;   ///< grandchildren moved into a free slot of their grandparent
    std::uint64_t exchanges = 0;  ///< grandchild <-> grandchild exchanges under two children
    std::uint64_t splits = 0;     ///< split_merge: leaves split in two
    std::uint64_t merges = 0;     ///< split_merge: all-leaf nodes collapsed into one leaf
};

/// Refit plus tree rotations in the same bottom-up pass (Kopta et al. 2012, §2), on the
/// project's 8-wide nodes. At each inner node N, after its children are refit (and rotated),
/// the pass applies the move that lowers the SAH most, up to max_rotations_per_node times.
/// Moves exchange whole subtrees between N's children and grandchildren, so only the boxes of
/// the one or two children they touch change, and the SAH changes by exactly those boxes'
/// change in half area (every other node keeps its box; N's box is the union of the same
/// triangles):
/// - swap: a child C of N trades places with a grandchild g under another child G (N's slot
///   of C takes g, G's slot of g takes C): Kensler's child/grandchild rotation, all 7 x 8
///   (C, g) pairs of each inner child G tried;
/// - exchange: grandchildren under two different children G and G2 trade places: Kensler's
///   compound grandchild/grandchild rotation, and on wide trees the move that trades
///   triangles between sibling bottom nodes. Each side's outlier (the child whose leaving
///   shrinks it most) is tried against every child of the other side;
/// - pull-up: when N has a free slot, a grandchild moves up into it; G shrinks and nothing
///   grows, so the SAH never rises (binary trees have no free slots, so no such move there).
/// Two exact bounds prune the search (they skip only moves that could not beat the best so far,
/// so the moves chosen are the same as without them): a move's gain is at most what G can
/// shrink by losing one child; and what a box X turns G into when it replaces any one of G's
/// children is at least G's "core" (the part every child-less-one box of G covers) plus X,
/// which rules out at one box-area each the swaps and exchanges that would bring in a box from
/// far away (most of them in a coherent tree). The pass is deterministic (the decisions at N depend
/// only on N's subtree) and keeps every triangle in exactly one leaf and the nesting within
/// max_depth. Keeps per-node heights and searched areas between calls (no allocation after the
/// first call on a tree of the same size).
class BvhRotator {
public:
    /// Refits `bvh` to `mesh` (see refit_object_bvh) and rotates in the same pass.
    /// Throws rebraid::Error on invalid settings or a mesh of another triangle count.
    RotationPassStats refit_and_rotate(const Mesh& mesh, ObjectBvh& bvh,
                                       const RotationSettings& settings = {});

    /// Forgets what was searched: call after the tree was replaced (e.g. rebuilt).
    void reset();

private:
    std::vector<std::uint8_t> heights_;  ///< per node id: inner levels of its subtree
    std::vector<float> searched_areas_;  ///< per node id: children's areas at its last search
};

}  // namespace rebraid
