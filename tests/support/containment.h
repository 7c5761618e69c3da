#pragma once

// Exact containment of the two-level structures: every box of a top level must hold the
// world-space triangles below it. Reachability (reachability.h) proves each triangle is
// reached once per reference; this proves no box test can cull a triangle the ray would hit.
// Triangles that spatial splits cut into parts (several references in their object BVH) are
// left out: each box holds only the part below it, which the hit comparisons check.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid::test {

/// Per primID of `bvh`'s mesh: whether the BVH holds it more than once (cut by spatial splits).
inline std::vector<bool> cut_triangles(const ObjectBvh& bvh) {
    PrimId largest = 0;
    for (const PrimId prim : bvh.prim_ids) largest = std::max(largest, prim);
    std::vector<int> references(bvh.prim_ids.empty() ? 0 : largest + 1, 0);
    for (const PrimId prim : bvh.prim_ids) ++references[prim];
    std::vector<bool> cut(references.size());
    for (std::size_t p = 0; p < references.size(); ++p) cut[p] = references[p] > 1;
    return cut;
}

/// Calls `visit(corner)` for every corner of every triangle below `ref` of `bvh` but those
/// `cut` marks.
template <class Visit>
void for_each_corner_below(const ObjectBvh& bvh, const std::vector<bool>& cut, NodeRef ref,
                           Visit&& visit) {
    if (ref.is_empty()) return;
    if (ref.is_leaf()) {
        for (std::uint32_t i = 0; i < ref.prim_count(); ++i) {
            if (cut[bvh.prim_ids[ref.first_prim() + i]]) continue;
            const TriangleVerts& tri = bvh.triangles[ref.first_prim() + i];
            visit(tri.v0);
            visit(tri.v1);
            visit(tri.v2);
        }
        return;
    }
    for (NodeRef child : bvh.nodes[ref.node_id()].children)
        for_each_corner_below(bvh, cut, child, visit);
}

/// Walks the whole top level of `accel`: each inner slot's box holds the boxes of the node it
/// points to, each leaf slot's box holds every world-space corner of every triangle below
/// every item of the leaf (exactly: no tolerance, the corners rounded as the builders'
/// transform_point rounds them). Reports the first few violations; returns how many boxes were
/// checked.
inline std::size_t expect_boxes_enclose_geometry(const Scene& scene, const InstancedAccel& accel,
                                                 const std::string& what) {
    const TopLevelBvh& top = accel.top_level();
    std::size_t checked = 0, violations = 0;
    const auto fail = [&](const std::string& message) {
        if (++violations <= 5) ADD_FAILURE() << what << ": " << message;
    };
    if (top.root.is_empty()) return 0;
    std::vector<std::vector<bool>> cut;
    for (const ObjectBvh& bvh : accel.object_bvhs()) cut.push_back(cut_triangles(bvh));
    // The root itself has no box a ray is tested against: start with an unbounded one.
    constexpr float kInf = std::numeric_limits<float>::infinity();
    std::vector<std::pair<NodeRef, BBox3f>> pending = {
        {top.root, BBox3f{{-kInf, -kInf, -kInf}, {kInf, kInf, kInf}}}};
    while (!pending.empty()) {
        const auto [ref, box] = pending.back();
        pending.pop_back();
        ++checked;
        if (ref.is_inner()) {
            const WideNode& node = top.nodes[ref.node_id()];
            for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
                const BBox3f child_box = node.child_bounds(slot);
                if (!box.contains(child_box)) {
                    const float excess =
                        std::max({box.min.x - child_box.min.x, child_box.max.x - box.max.x,
                                  box.min.y - child_box.min.y, child_box.max.y - box.max.y,
                                  box.min.z - child_box.min.z, child_box.max.z - box.max.z});
                    fail("node " + std::to_string(ref.node_id()) + " slot " + std::to_string(slot) +
                         ": box " + std::to_string(excess) + " outside its parent's (extent " +
                         std::to_string(length(box.extent())) + ")");
                }
                pending.push_back({node.children[slot], child_box});
            }
            continue;
        }
        for (std::uint32_t i = 0; i < ref.prim_count(); ++i) {
            const TopLevelItem& item = top.items[ref.first_prim() + i];
            const Instance& instance = scene.instances[item.instance_id];
            const MeshId mesh = instance.mesh_id;
            const ObjectBvh& bvh = accel.object_bvhs()[mesh];
            // Farthest a corner, rounded as the builders' transform_point rounds it, lies
            // outside the box.
            float excess = 0.0f;
            // A copy: lambdas may capture structured bindings only from clang 16 on.
            const BBox3f leaf_box = box;
            for_each_corner_below(bvh, cut[mesh], item.object_node, [&](Vec3f corner) {
                const Vec3f p = instance.object_to_world.transform_point(corner);
                excess = std::max({excess, leaf_box.min.x - p.x, p.x - leaf_box.max.x,
                                   leaf_box.min.y - p.y, p.y - leaf_box.max.y, leaf_box.min.z - p.z,
                                   p.z - leaf_box.max.z});
            });
            if (excess > 0.0f)
                fail("item " + std::to_string(ref.first_prim() + i) + " (instance " +
                     std::to_string(item.instance_id) + "): a world-space corner lies " +
                     std::to_string(excess) + " outside its leaf's box (extent " +
                     std::to_string(length(box.extent())) + ")");
        }
    }
    EXPECT_EQ(violations, 0u) << what;
    return checked;
}

}  // namespace rebraid::test
