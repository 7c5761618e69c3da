#pragma once

#include <cstdint>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// Parameters of refit_object_bvh().
struct RefitSettings {
    /// Wide levels (from the root) whose children are refit as parallel tasks; below, one
    /// task refits its whole subtree. 3 levels give up to 8^3 tasks, plenty for a few cores.
    /// The result does not depend on this value or on the thread count.
    int parallel_depth = 3;
};

/// What one bottom-up pass learnt about a subtree.
struct SubtreeRefit {
    BBox3f bounds;
    /// Unnormalised SAH cost (as object_bvh_sah(): half area per inner node, half area times
    /// triangle count per leaf), summed in a fixed order so it is the same on any thread count.
    double cost = 0.0;
};

/// Recomputes the leaf `leaf`'s triangle copies (ObjectBvh::triangles, leaf order) from
/// `mesh` and returns their bounds.
BBox3f refit_leaf(const Mesh& mesh, ObjectBvh& bvh, NodeRef leaf);

/// Refits `bvh` after `mesh`'s positions changed (same triangles, same topology as when it
/// was built): refreshes the leaf-order triangle copies and recomputes every node's child
/// boxes bottom up, and `bvh.bounds`. Subtrees run as TBB tasks; min/max are exact, so the
/// result is bit-identical on any thread count. Allocates nothing. Returns the SAH of the
/// refit tree (normalised by the root's half area; 0 for an empty tree).
/// Throws rebraid::Error when `mesh` does not have the BVH's triangle count.
double refit_object_bvh(const Mesh& mesh, ObjectBvh& bvh, const RefitSettings& settings = {});

/// Throws rebraid::Error, naming `caller`, when `mesh` cannot be the mesh `bvh` was built
/// for (a different triangle count). Shared by every update of an ObjectBvh.
void check_mesh_matches(const Mesh& mesh, const ObjectBvh& bvh, const char* caller);

}  // namespace rebraid
