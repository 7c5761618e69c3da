#pragma once

// Counting how often each (instance, primitive) pair is reachable from the root of a
// structure: every triangle of every instance must be reachable, each of its references in
// the BVH that holds it exactly once (a triangle cut by spatial splits has a reference in each
// leaf that holds a part of it; others have one).

#include <gtest/gtest.h>

#include <span>
#include <vector>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/scene.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid::test {

/// Calls visit(leaf) for every leaf reference below `ref`.
template <class Visit>
void for_each_leaf(std::span<const WideNode> nodes, NodeRef ref, Visit&& visit) {
    if (ref.is_empty()) return;
    if (ref.is_leaf()) {
        visit(ref);
        return;
    }
    for (NodeRef child : nodes[ref.node_id()].children) for_each_leaf(nodes, child, visit);
}

/// Per instance and primID: how often the structure reaches the triangle, and how many
/// references to it the BVH it is traced in holds.
struct ReachCounts {
    std::vector<std::vector<int>> reached, held;  // [instance][primID]
};

inline ReachCounts empty_counts(const Scene& scene) {
    ReachCounts counts;
    counts.reached.resize(scene.instances.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
        counts.reached[i].assign(scene.meshes[scene.instances[i].mesh_id].triangles.size(), 0);
    counts.held = counts.reached;
    return counts;
}

inline ReachCounts reach_counts(const Scene& scene, const InstancedAccel& accel) {
    ReachCounts counts = empty_counts(scene);
    const TopLevelBvh& top = accel.top_level();
    for_each_leaf(top.nodes, top.root, [&](NodeRef leaf) {
        for (std::uint32_t i = 0; i < leaf.prim_count(); ++i) {
            const TopLevelItem& item = top.items[leaf.first_prim() + i];
            const ObjectBvh& bvh = accel.object_bvhs()[accel.instance_meshes()[item.instance_id]];
            for_each_leaf(bvh.nodes, item.object_node, [&](NodeRef object_leaf) {
                for (std::uint32_t p = 0; p < object_leaf.prim_count(); ++p)
                    ++counts.reached[item.instance_id][bvh.prim_ids[object_leaf.first_prim() + p]];
            });
        }
    });
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
        for (const PrimId prim : accel.object_bvhs()[accel.instance_meshes()[i]].prim_ids)
            ++counts.held[i][prim];
    return counts;
}

inline ReachCounts reach_counts(const Scene& scene, const FlatAccel& accel) {
    ReachCounts counts = empty_counts(scene);
    const ObjectBvh& bvh = accel.bvh();
    for_each_leaf(bvh.nodes, bvh.root, [&](NodeRef leaf) {
        for (std::uint32_t p = 0; p < leaf.prim_count(); ++p) {
            const PrimId world = bvh.prim_ids[leaf.first_prim() + p];
            ++counts.reached[accel.triangle_instances()[world]][accel.triangle_prims()[world]];
        }
    });
    for (const PrimId world : bvh.prim_ids)
        ++counts.held[accel.triangle_instances()[world]][accel.triangle_prims()[world]];
    return counts;
}

/// Every triangle held at least once, and reached once per reference.
inline void expect_each_reached_once(const ReachCounts& counts) {
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < counts.reached.size(); ++i)
        for (std::size_t p = 0; p < counts.reached[i].size(); ++p)
            if ((counts.held[i][p] < 1 || counts.reached[i][p] != counts.held[i][p]) &&
                ++wrong <= 5)
                ADD_FAILURE() << "instance " << i << " prim " << p << " reached "
                              << counts.reached[i][p] << " times, held " << counts.held[i][p]
                              << " times";
    EXPECT_EQ(wrong, 0u);
}

}  // namespace rebraid::test
