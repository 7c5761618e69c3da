// Helpers shared by the tests of object-BVH updates (object_bvh_update_test.cpp,
// treelet_sampling_test.cpp): deforming meshes and checks that an updated tree is valid and
// answers rays as Embree flat does.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/bvh/leaf_row_hints.h"
#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/object_subtree_counts.h"
#include "rebraid/core/random.h"
#include "rebraid/core/structure_hash.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/top_level/instanced_accel.h"
#include "rebraid/top_level/two_level_builder.h"
#include "support/hit_comparison.h"
#include "support/test_rays.h"

namespace rebraid::test {

inline Mesh rest_mesh() {
    return make_torus_knot({.path_segment_count = 192, .tube_segment_count = 10});
}

/// The rest mesh at animation time t: twisted about Y, then each vertex thrown along its own
/// random direction by `explode` * t (incoherent motion, what degrades a refit tree).
inline Mesh deformed(const Mesh& rest, float t, float explode = 0.6f) {
    Mesh mesh = rest;
    Random random(99);
    for (Vec3f& p : mesh.positions) {
        const float angle = 1.5f * t * p.y;
        const float c = std::cos(angle), s = std::sin(angle);
        p = {c * p.x + s * p.z, p.y, -s * p.x + c * p.z};
        const Vec3f direction{random.next_float(-1, 1), random.next_float(-1, 1),
                              random.next_float(-1, 1)};
        p = p + direction * (explode * t);
    }
    return mesh;
}

/// The rest mesh with its own three corners per triangle (so triangles can move apart).
inline Mesh unwelded(const Mesh& rest) {
    Mesh mesh;
    mesh.name = rest.name + " unwelded";
    for (std::uint32_t prim = 0; prim < rest.triangles.size(); ++prim) {
        const auto base = std::uint32_t(mesh.positions.size());
        for (const Vec3f& corner : rest.corners(prim)) mesh.positions.push_back(corner);
        mesh.triangles.push_back({base, base + 1, base + 2});
    }
    return mesh;
}

/// Each triangle of an unwelded mesh moved rigidly by `blend` of the way to another
/// triangle's place: triangles stay small but their neighbours change, the worst case for
/// a tree built on the rest pose.
inline Mesh shuffled(const Mesh& unwelded_rest, float blend) {
    Mesh mesh = unwelded_rest;
    const auto count = std::uint32_t(mesh.triangles.size());
    Random random(7);
    std::vector<std::uint32_t> other(count);
    for (std::uint32_t i = 0; i < count; ++i) other[i] = i;
    for (std::uint32_t i = count; i > 1; --i) std::swap(other[i - 1], other[random.next_below(i)]);
    const auto center = [&](std::uint32_t prim) {
        const auto c = unwelded_rest.corners(prim);
        return (c[0] + c[1] + c[2]) * (1.0f / 3.0f);
    };
    for (std::uint32_t prim = 0; prim < count; ++prim) {
        const Vec3f offset = (center(other[prim]) - center(prim)) * blend;
        for (std::uint32_t vertex : mesh.triangles[prim])
            mesh.positions[vertex] = mesh.positions[vertex] + offset;
    }
    return mesh;
}

/// Checks the child boxes below `ref` contain their subtree; returns the subtree's depth.
inline int check_subtree(const ObjectBvh& bvh, NodeRef ref, const BBox3f& box,
                         std::vector<int>& reached, std::size_t& errors) {
    if (ref.is_leaf()) {
        for (std::uint32_t i = ref.first_prim(); i < ref.first_prim() + ref.prim_count(); ++i) {
            ++reached[bvh.prim_ids[i]];
            BBox3f tri;
            tri.extend(bvh.triangles[i].v0), tri.extend(bvh.triangles[i].v1);
            tri.extend(bvh.triangles[i].v2);
            if (!box.contains(tri) && ++errors <= 5)
                ADD_FAILURE() << "leaf box misses triangle at leaf-order " << i;
        }
        return 0;
    }
    const WideNode& node = bvh.nodes[ref.node_id()];
    if (!box.contains(node.bounds()) && ++errors <= 5)
        ADD_FAILURE() << "node " << ref.node_id() << " is not inside its parent's box";
    int depth = 0, count = node.child_count();
    if (count < 1 && ++errors <= 5) ADD_FAILURE() << "node " << ref.node_id() << " is empty";
    for (int slot = count; slot < kBvhWidth; ++slot)
        if (!node.children[slot].is_empty() && ++errors <= 5)
            ADD_FAILURE() << "node " << ref.node_id() << " has a used slot after a free one";
    for (int slot = 0; slot < count; ++slot)
        depth = std::max(depth, check_subtree(bvh, node.children[slot], node.child_bounds(slot),
                                              reached, errors));
    return depth + 1;
}

/// The tree is valid for `mesh`: each triangle in exactly one leaf, triangle copies equal to
/// the mesh's, every box containing what is below it, nesting within kMaxBvhDepth.
inline void expect_valid(const Mesh& mesh, const ObjectBvh& bvh) {
    ASSERT_EQ(bvh.prim_ids.size(), mesh.triangles.size());
    ASSERT_EQ(bvh.triangles.size(), mesh.triangles.size());
    std::size_t errors = 0;
    for (std::size_t i = 0; i < bvh.prim_ids.size(); ++i) {
        const auto corners = mesh.corners(bvh.prim_ids[i]);
        const TriangleVerts& copy = bvh.triangles[i];
        if ((copy.v0 != corners[0] || copy.v1 != corners[1] || copy.v2 != corners[2]) &&
            ++errors <= 5)
            ADD_FAILURE() << "stale triangle copy at leaf-order " << i;
    }
    std::vector<int> reached(mesh.triangles.size(), 0);
    const int depth = check_subtree(bvh, bvh.root, bvh.bounds, reached, errors);
    EXPECT_LE(depth, kMaxBvhDepth);
    for (std::size_t p = 0; p < reached.size(); ++p)
        if (reached[p] != 1 && ++errors <= 5)
            ADD_FAILURE() << "prim " << p << " reached " << reached[p] << " times";
    EXPECT_EQ(errors, 0u);
    EXPECT_EQ(bvh.bounds, mesh.bounds());
    // The counts re-braiding weighs BRefs by are in step with the nodes.
    if (!bvh.node_prim_counts.empty()) {
        EXPECT_TRUE(bvh.node_prim_counts == subtree_prim_counts(bvh))
            << "node triangle counts out of step with the nodes";
    }
    // The pre-arranged rows the SIMD kernels read are in step with the corners and leaves.
    if (bvh.leaf_rows.empty()) return;  // BuildSettings::pre_arranged_leaves off
    EXPECT_TRUE(bvh.leaf_rows == make_leaf_rows(bvh.nodes, bvh.root, bvh.triangles, bvh.prim_ids))
        << "leaf rows out of step with the triangles or the leaves";
    // So are the hints the traversal prefetches those rows by.
    std::vector<WideNode> hinted = bvh.nodes;
    write_leaf_row_hints(hinted);
    std::size_t stale_hints = 0;
    for (std::size_t n = 0; n < hinted.size(); ++n)
        for (int slot = 0; slot < kBvhWidth; ++slot)
            stale_hints += hinted[n].leaf_row_hints[slot] != bvh.nodes[n].leaf_row_hints[slot];
    EXPECT_EQ(stale_hints, 0u) << "leaf-row hints out of step with the leaves";
}

/// The tree answers `ray_count` varied rays around `ray_box` (test_rays.h; closest hit and
/// occlusion) as Embree flat built on the same mesh, within `tolerance`.
inline void expect_hits_of_embree_flat(const Mesh& mesh, const ObjectBvh& bvh,
                                       const BBox3f& ray_box, std::size_t ray_count,
                                       std::uint64_t seed, const Tolerance& tolerance) {
    Scene scene;
    scene.meshes.push_back(mesh);
    scene.instances.push_back({0, AffineTransform::identity()});
    std::vector<ObjectBvh> bvhs{bvh};
    TopLevelBvh top = build_two_level(scene, bvhs);
    const InstancedAccel tested(scene, std::move(bvhs), std::move(top), AccelStats{});
    const glue::EmbreeFlatAccel reference(scene);
    const std::vector<Ray> rays = varied_rays(reference, ray_box, ray_count, seed);
    expect_same_answers(scene, rays, trace_all(reference, rays), trace_all(tested, rays),
                        tolerance);
}

/// The updated tree answers 10,000 varied rays as Embree flat built on the same deformed frame.
inline void expect_hits_of_embree_flat(const Mesh& mesh, const ObjectBvh& bvh) {
    expect_hits_of_embree_flat(mesh, bvh, mesh.bounds(), 10000, 5, tolerance_for(mesh.bounds()));
}

inline std::uint64_t structure_hash(const ObjectBvh& bvh) {
    StructureHash hash;
    hash.add<WideNode>(bvh.nodes);
    hash.add_value(bvh.root);
    hash.add<PrimId>(bvh.prim_ids);
    hash.add<TriangleVerts>(bvh.triangles);
    return hash.value();
}

}  // namespace rebraid::test
