#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/object_subtree_counts.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/transform.h"
#include "rebraid/rebraiding/bref.h"
#include "rebraid/rebraiding/bref_bounds.h"
#include "rebraid/rebraiding/bref_child_bounds.h"

namespace rebraid {

/// The object BVHs BRefs point into, where each instance places its mesh, and how BRefs open.
struct BRefSource {
    std::span<const ObjectBvh> object_bvhs;  ///< index = MeshId
    std::span<const Instance> instances;     ///< the scene's; index = InstanceId
    BRefBoundsRule bounds_rule = BRefBoundsRule::transformed_box;
    /// Triangles below each object node (object_subtree_counts.h), counted per mesh when
    /// first needed. Null: children get the paper's estimate, parent count / number of
    /// children (§5.3).
    const LazySubtreeCounts* subtree_counts = nullptr;
    /// Leaves of several triangles open into one BRef per triangle.
    bool open_leaves = false;
    /// Optional, per target slot (rebraid_cost_guard.h): what the BRef's object node costs
    /// inside its instance (mapped half area, times its triangles for a leaf), and the sum
    /// of that cost over the BRefs opened in the slot. Written by open_brefs when not empty.
    std::span<double> node_cost;
    std::span<double> removed_cost;
    /// Optional, per mesh: support tables for the world boxes of its top nodes (empty: none).
    std::span<const ObjectSupportTables> support_tables;
    /// Optional: the children's world boxes of BRefs to inner nodes, computed once per BRef.
    BRefChildBounds* child_bounds = nullptr;

    MeshId mesh_of(const BRefTarget& target) const { return instances[target.instance_id].mesh_id; }
    const ObjectBvh& bvh_of(const BRefTarget& target) const { return object_bvhs[mesh_of(target)]; }
    const AffineTransform& object_to_world(InstanceId instance) const {
        return instances[instance].object_to_world;
    }
    /// The world box of a BRef to `node` (whose object box is `node_box`) of the instance of
    /// `target`, by the bounds rule.
    BBox3f world_bounds(const BRefTarget& target, NodeRef node, const BBox3f& node_box) const {
        const MeshId mesh = mesh_of(target);
        return bref_world_bounds(object_bvhs[mesh], node, node_box,
                                 object_to_world(target.instance_id), bounds_rule,
                                 support_tables.empty() ? nullptr : &support_tables[mesh]);
    }
    bool has_exact_counts() const { return subtree_counts != nullptr; }
    bool is_tracking_costs() const { return !node_cost.empty(); }
};

/// True when a BRef to `node` can be opened: an inner node, or with `open_leaves` a leaf of
/// more than one triangle.
inline bool is_openable(NodeRef node, bool open_leaves) {
    return node.is_inner() || (open_leaves && node.is_leaf() && node.prim_count() > 1);
}

/// How many BRefs opening `target` turns it into (its children, or a leaf's triangles).
/// Precondition: is_openable(target.object_node, source.open_leaves).
inline std::uint32_t bref_child_count(const BRefSource& source, const BRefTarget& target) {
    const NodeRef node = target.object_node;
    if (node.is_leaf()) return node.prim_count();
    return std::uint32_t(source.bvh_of(target).nodes[node.node_id()].child_count());
}

/// Calls visit(child, object_box) for each BRef opening `target` makes, in order: an inner
/// node's children with the boxes it stores, or a leaf's triangles as leaf references of one
/// triangle with their corners' box. Same precondition as bref_child_count.
template <class Visit>
void for_each_bref_child(const BRefSource& source, const BRefTarget& target, Visit&& visit) {
    const ObjectBvh& bvh = source.bvh_of(target);
    const NodeRef node = target.object_node;
    if (node.is_leaf()) {
        for (std::uint32_t i = node.first_prim(); i < node.first_prim() + node.prim_count(); ++i) {
            const TriangleVerts& t = bvh.triangles[i];
            BBox3f box;
            box.extend(t.v0);
            box.extend(t.v1);
            box.extend(t.v2);
            visit(NodeRef::leaf(i, 1), box);
        }
        return;
    }
    const WideNode& wide = bvh.nodes[node.node_id()];
    for (int c = 0; c < kBvhWidth && !wide.children[c].is_empty(); ++c)
        visit(wide.children[c], wide.child_bounds(c));
}

/// for_each_bref_child with each child's world box: visit(child, object_box, world_box).
/// `slot` is `target`'s slot; the boxes of an inner node's children come from
/// source.child_bounds when set (computed there on first use).
template <class Visit>
void for_each_bref_child_bounds(const BRefSource& source, std::uint32_t slot,
                                const BRefTarget& target, Visit&& visit) {
    const NodeRef node = target.object_node;
    if (node.is_leaf() || !source.child_bounds) {
        for_each_bref_child(source, target, [&](NodeRef child, const BBox3f& box) {
            visit(child, box, source.world_bounds(target, child, box));
        });
        return;
    }
    const WideNode& wide = source.bvh_of(target).nodes[node.node_id()];
    const BRefChildBounds::Boxes* boxes = source.child_bounds->find(slot, target);
    if (!boxes) {
        BRefChildBounds::Boxes computed;
        for (int c = 0; c < kBvhWidth && !wide.children[c].is_empty(); ++c)
            computed[c] = source.world_bounds(target, wide.children[c], wide.child_bounds(c));
        boxes = &source.child_bounds->store(slot, target, computed);
    }
    for (int c = 0; c < kBvhWidth && !wide.children[c].is_empty(); ++c)
        visit(wide.children[c], wide.child_bounds(c), (*boxes)[c]);
}

/// Triangles below `node` of the BVH of `target`'s instance, from source.subtree_counts
/// (precondition: has_exact_counts()).
inline std::uint32_t exact_prim_count(const BRefSource& source, const BRefTarget& target,
                                      NodeRef node) {
    return source.subtree_counts->prim_count(source.mesh_of(target), node);
}

}  // namespace rebraid
