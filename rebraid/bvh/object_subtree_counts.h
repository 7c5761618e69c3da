#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// Triangles below each inner node of `bvh` (index = node id; leaf references below count
/// their triangles, so with spatial splits a triangle counts once per leaf holding it). One
/// pass over the nodes (a linear one in reverse id order when every child has a larger id
/// than its parent, as the project's builders number them; a walk from the root otherwise).
std::vector<std::uint32_t> subtree_prim_counts(const ObjectBvh& bvh);

/// subtree_prim_counts for every mesh that `instances` of `scene` use; empty vectors for the
/// others (their BVHs are never opened). Meshes in parallel.
std::vector<std::vector<std::uint32_t>> subtree_prim_counts(const Scene& scene,
                                                            std::span<const ObjectBvh> object_bvhs,
                                                            std::span<const InstanceId> instances);

/// Triangles below one object-BVH reference, given the counts of its BVH's nodes (an empty
/// `node_prims` is allowed when `ref` is the root or a leaf).
std::uint32_t object_ref_prim_count(const ObjectBvh& bvh, NodeRef ref,
                                    std::span<const std::uint32_t> node_prims);

/// subtree_prim_counts of a set of object BVHs: the counts a BVH keeps
/// (ObjectBvh::node_prim_counts, made by the builders and kept in step by the updates that
/// regroup nodes), else computed the first time they are asked for (thread-safe, once per
/// mesh), so a re-braiding build counts only the meshes it actually opens BRefs of.
/// The BVHs must outlive this object and stay unchanged while it is used.
class LazySubtreeCounts {
public:
    explicit LazySubtreeCounts(std::span<const ObjectBvh> object_bvhs);

    /// Triangles below `node` of the BVH of `mesh` (a leaf's own count for a leaf).
    std::uint32_t prim_count(std::uint32_t mesh, NodeRef node) const {
        if (node.is_leaf()) return node.prim_count();
        return counts_of(mesh)[node.node_id()];
    }
    /// All inner-node counts of `mesh`'s BVH, computing them on first use.
    std::span<const std::uint32_t> counts_of(std::uint32_t mesh) const;
    /// Triangles a top-level item at `node` of the BVH of `mesh` stands for, by the rule of
    /// object_ref_prim_count: the mesh's triangle count at the root, a
    /// leaf's own count, zero for an empty reference; only an inner node below the root makes
    /// the mesh's counts (on first use). Throws rebraid::Error for a node the BVH lacks.
    std::uint32_t item_prim_count(std::uint32_t mesh, NodeRef node) const;

private:
    std::span<const ObjectBvh> object_bvhs_;
    mutable std::vector<std::vector<std::uint32_t>> counts_;
    std::unique_ptr<std::once_flag[]> computed_;
};

}  // namespace rebraid
