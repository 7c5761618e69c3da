#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// Parameters of SelectiveRestructurer::restructure().
struct RestructureSettings {
    /// Most triangles rebuilt per pass, as a fraction of the BVH's: bounds the pass's cost
    /// (about this fraction of a full rebuild, plus a metric pass).
    double max_rebuilt_fraction = 0.25;
    /// Subtrees of fewer triangles are never rebuilt: their benefit is small and rotations
    /// repair such local damage more cheaply.
    std::uint32_t min_subtree_prims = 64;
    /// A subtree is a candidate when its restructuring benefit (RM-IQ, see restructure())
    /// is at least this fraction of the whole tree's SAH.
    double min_relative_benefit = 0.001;
    /// Settings of the binned-SAH builder that rebuilds the chosen subtrees.
    BuildSettings build;

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// What one restructuring pass did.
struct RestructureStats {
    double sah = 0.0;              ///< SAH after the pass (as object_bvh_sah())
    std::uint32_t candidates = 0;  ///< subtrees whose benefit passed the threshold
    std::uint32_t subtrees_rebuilt = 0;
    /// Of those, subtrees over scattered leaf-order positions (single-triangle leaves).
    std::uint32_t scattered_subtrees_rebuilt = 0;
    std::uint64_t prims_rebuilt = 0;  ///< triangles in the rebuilt subtrees
};

/// Selective restructuring (Yoon, Curtis and Manocha 2007) on the project's wide BVHs:
/// finds the subtrees whose culling efficiency degraded most and rebuilds only those with
/// the binned-SAH builder, in place. Keeps scratch arrays between calls.
class SelectiveRestructurer {
public:
    /// Restructures `bvh`, which must already be refit to `mesh` (refit_object_bvh or
    /// BvhRotator). Steps:
    /// 1. one pass computes each node's CM-IQ (paper §4.1, Eq. 1: expected ray tests once the
    ///    node is hit; with the SAH's probabilities it is the node's SAH cost over its area);
    /// 2. each inner node N gets the RM-IQ benefit of restructuring its children (§4.2, Eq. 7),
    ///    summed over the pairs of N's child boxes: C(n1) * area(overlap) / area(root) for each
    ///    side, i.e. overlap assumed removed, probability taken relative to the root so nodes
    ///    anywhere compare (the wide form of the paper's node pairs: rebuilding N's subtree
    ///    re-partitions all of its children at once);
    /// 3. candidates (benefit >= min_relative_benefit * SAH, at least min_subtree_prims
    ///    triangles, either over one contiguous leaf-order range or in single-triangle
    ///    leaves, as in a pre-split tree after rotations) are taken greedily by benefit per
    ///    rebuild cost k log2 k (§4.3, f_rebuild), never nested, within max_rebuilt_fraction;
    /// 4. the chosen subtrees are rebuilt in parallel (single-triangle leaves stay single)
    ///    and spliced in, keeping N's node id and the leaf-order positions of its triangles,
    ///    each only when its SAH cost actually fell, so the pass never raises the SAH.
    ///    Deterministic for any thread count.
    /// Throws rebraid::Error on invalid settings or a mesh of another triangle count.
    RestructureStats restructure(const Mesh& mesh, ObjectBvh& bvh,
                                 const RestructureSettings& settings = {});

private:
    /// Per node id, from the metric pass.
    struct NodeInfo {
        double cost = 0.0;                 ///< SAH cost of the subtree (half-area units)
        std::uint32_t parent = 0;          ///< parent node id (the root's is itself)
        std::uint32_t prim_count = 0;      ///< triangles below
        std::uint32_t largest_leaf = 0;    ///< most triangles in one leaf below
        std::uint32_t first = 0, end = 0;  ///< span of the leaf ranges below
        std::uint16_t depth = 0;           ///< inner levels above
        bool is_reachable = false;
        bool is_chosen = false;  ///< chosen for rebuilding
        bool is_taken = false;   ///< chosen, or an ancestor of a chosen node
    };
    /// A subtree worth rebuilding.
    struct Candidate {
        std::uint32_t node_id = 0;
        double score = 0.0;  ///< benefit per unit of rebuild cost
    };

    double measure(const ObjectBvh& bvh, NodeRef ref, const BBox3f& box, std::uint32_t parent,
                   int depth);

    std::vector<NodeInfo> info_;
    std::vector<Candidate> candidates_;
};

}  // namespace rebraid
