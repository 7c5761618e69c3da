#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// Parameters of TreeletSampler::optimize().
struct TreeletSettings {
    /// Treelet roots drawn per pass, as a fraction of the tree's inner nodes (at least one
    /// draw; a root drawn twice counts once). More draws repair more per pass at a
    /// proportional cost: each draw grows and rebuilds one treelet.
    double root_fraction = 0.02;
    /// A treelet grows until it has this many subtrees below it (2..64). Larger treelets can
    /// untangle more at once; their rebuild costs about n log n in this count.
    std::uint32_t max_treelet_leaves = 64;
    /// alpha of the sampling weight p(N) = growth of N's children's areas + alpha * (p of
    /// N's inner children): how much damage deeper down draws a root upwards (paper: p(N)).
    double descendant_weight = 0.5;
    /// A rebuilt treelet is kept only when it lowers the SAH cost by more than this fraction
    /// of its root's half area (float noise must not count as a gain).
    float min_relative_gain = 1e-5f;
    /// Seed of the root draws; pass k of a sampler draws with seed + k, so the result depends
    /// on the seed and the pass count only, never on the thread count.
    std::uint64_t seed = 1;

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// What one treelet-sampling pass did.
struct TreeletStats {
    double sah = 0.0;                 ///< SAH after the pass (as object_bvh_sah())
    std::uint32_t sampled = 0;        ///< distinct treelet roots drawn
    std::uint32_t improved = 0;       ///< of those, treelets whose rebuild lowered the SAH
    std::uint32_t applied = 0;        ///< non-overlapping treelets spliced in
    std::uint64_t nodes_rebuilt = 0;  ///< inner nodes of the applied treelets (before)
};

/// Treelet sampling (Barbier and Paulin, "BVH updates using treelet sampling"), on the
/// project's 8-wide nodes. After a refit, one pass:
/// 1. weighs each inner node N by how much its children's boxes grew since N was last part
///    of a drawn treelet (or since the tree was built) plus descendant_weight times its inner
///    children's weights (the paper's p(N) = dArea(N_L) + dArea(N_R) + alpha (p(N_L) +
///    p(N_R)), computed bottom up). Caching the areas when a node was last examined rather
///    than every frame lets slow damage add up until it is drawn, and keeps a pass from
///    drawing the same healthy treelets again;
/// 2. draws treelet roots with probability proportional to the weights (seeded, serial);
/// 3. grows a treelet from each root by opening its largest-area inner node until it
///    reaches max_treelet_leaves subtrees, then rebuilds the treelet's inner nodes over
///    those subtrees (exact SAH sweeps, grown into wide nodes like every builder of the
///    project), in parallel, without writing to the tree; the reward is the decrease in
///    the summed half areas of the treelet's inner nodes (its subtrees keep their costs);
/// 4. picks the set of non-overlapping treelets of largest total reward. Treelets are
///    connected and rooted, so two overlap exactly when one's root lies in the other; the
///    overlap graph is the chordal graph the paper solves by isolated-weight transfer, and
///    here a bottom-up pass over the tree solves it exactly: best(N) = max(sum of best over
///    N's inner children, reward(T_N) + sum of best over T_N's inner subtrees);
/// 5. splices the chosen treelets in, reusing their node ids (a treelet's root keeps its
///    id, so no parent changes).
/// Triangles, leaves and leaf order are untouched, so it works on trees with any leaf size,
/// but it cannot separate triangles that share a leaf (on an exploding mesh most of the
/// damage is there: bench_update; rebuild or restructure repair that).
/// A treelet is applied only when it does not make its subtree deeper, so the nesting never
/// grows past what the builder made. Deterministic for any thread count. Keeps per-node
/// state (the cached areas of step 1) and scratch between calls.
class TreeletSampler {
public:
    /// One pass over `bvh`, which must already be refit to `mesh` (refit_object_bvh or
    /// BvhRotator). Never raises the SAH. Throws rebraid::Error on invalid settings or a mesh
    /// of another triangle count.
    TreeletStats optimize(const Mesh& mesh, ObjectBvh& bvh, const TreeletSettings& settings = {});

    /// Forgets the cached areas and the pass count: call after the tree was replaced. The
    /// next pass takes the boxes it finds as undamaged.
    void reset();
    /// As reset(), but takes `fresh` (e.g. just built) as the undamaged state, so the next
    /// pass sees the growth from it: call right after a rebuild, before refitting.
    void reset(const ObjectBvh& fresh);

private:
    /// A drawn treelet, grown and rebuilt, waiting for selection.
    struct Treelet {
        std::uint32_t root = 0;                ///< node id of its root
        std::vector<std::uint32_t> inner_ids;  ///< its inner node ids, root first
        std::vector<NodeRef> subtrees;         ///< the subtrees below it
        std::vector<BBox3f> subtree_boxes;
        std::vector<std::uint32_t> order;     ///< build scratch: subtree indices, sorted per axis
        std::vector<std::uint8_t> goes_left;  ///< build scratch: per subtree
        std::vector<std::uint32_t> scratch;   ///< build scratch: partition buffer
        /// The rebuilt inner nodes, local ids (0 = root); leaf references name subtrees
        /// (NodeRef::leaf(subtree index, 1)).
        std::vector<WideNode> built;
        double reward = 0.0;  ///< decrease of the SAH cost (half-area units), <= 0 if none
    };

    /// Per node id, from the weighing pass.
    struct NodeInfo {
        double weight = 0.0;        ///< p(N)
        double best = 0.0;          ///< best total reward of treelets inside the subtree
        std::uint32_t treelet = 0;  ///< 1 + index into treelets_ when N was drawn, else 0
        std::uint16_t depth = 0;
        std::uint8_t height = 0;  ///< inner levels of the subtree (1 for a bottom node)
        bool is_reachable = false;
        bool takes_treelet = false;  ///< best(N) takes N's treelet
    };

    /// Step 1 for the subtree at `node_id`: fills info_, returns p(N) and adds the subtree's
    /// SAH cost below N's own box to `cost`.
    double weigh(const ObjectBvh& bvh, std::uint32_t node_id, int depth, double alpha,
                 double& cost);
    /// Step 4: best(N) of the subtree at `node_id`, bottom up.
    double choose(const ObjectBvh& bvh, std::uint32_t node_id);
    /// Step 4: the treelets best() took, top down.
    void collect_chosen(const ObjectBvh& bvh, std::uint32_t node_id,
                        std::vector<std::uint32_t>& chosen) const;

    std::vector<NodeInfo> info_;
    /// Per node id: its children's summed half areas when last examined (< 0: unseen).
    std::vector<float> cached_areas_;
    std::vector<Treelet> treelets_;
    std::uint64_t pass_count_ = 0;
};

}  // namespace rebraid
