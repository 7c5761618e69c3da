// World bounds of instanced object nodes from their transformed vertices (tighter
// instance bounds), found by branch and bound, against a pass over every vertex.
#include "rebraid/bvh/vertex_world_bounds.h"
#include "rebraid/bvh/object_bvh_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/random.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/rebraiding/bref_bounds.h"
#include "support/placed_vertices.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

/// Every inner and leaf reference of `bvh` with its object-space box, root first.
struct NodeWithBox {
    NodeRef ref;
    BBox3f box;
};

std::vector<NodeWithBox> every_node(const ObjectBvh& bvh) {
    std::vector<NodeWithBox> nodes{{bvh.root, bvh.bounds}};
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        if (!nodes[i].ref.is_inner()) continue;
        const WideNode& node = bvh.nodes[nodes[i].ref.node_id()];
        for (int c = 0; c < kBvhWidth && !node.children[c].is_empty(); ++c)
            nodes.push_back({node.children[c], node.child_bounds(c)});
    }
    return nodes;
}

/// Checks vertex_world_bounds at `tolerance` on every node of a tree mesh under rotated,
/// scaled, mirrored and translated placements: it holds every transformed vertex and lies
/// within the tolerance of the node's extent (plus rounding padding) of their box.
void check_every_node(float tolerance) {
    const ObjectBvh bvh = build_object_bvh(make_tree({}));
    Random random(7);
    for (int trial = 0; trial < 8; ++trial) {
        const AffineTransform to_world = test::random_transform(random, 50.0f, trial % 2 == 1);
        for (const NodeWithBox& node : every_node(bvh)) {
            const BBox3f bounds = vertex_world_bounds(bvh, node.ref, node.box, to_world, tolerance);
            const BBox3f reference = test::placed_vertex_bounds(bvh, node.ref, to_world);
            ASSERT_TRUE(bounds.contains(reference)) << "trial " << trial;
            // The node's transformed box bounds its extent along every row of the transform.
            const Vec3f extent = to_world.transform_bbox(node.box).extent();
            const float allowed = tolerance * std::max({extent.x, extent.y, extent.z}) + 1e-4f;
            EXPECT_LE(test::largest_gap(bounds, reference), allowed) << "trial " << trial;
        }
    }
}

TEST(VertexWorldBounds, ToleranceZeroIsTheBoxOfTheVertices) {
    check_every_node(0.0f);
}

TEST(VertexWorldBounds, DefaultToleranceHoldsEveryVertexWithinOnePercent) {
    check_every_node(0.01f);
}

TEST(VertexWorldBounds, LeafRowsGiveTheBitsOfTheCorners) {
    // Leaves of up to 16 triangles (two row chunks) searched from the pre-arranged rows and
    // from the corner copies: the same support values and vertices, bit for bit.
    BuildSettings settings;
    settings.max_leaf_size = 16;
    settings.intersection_cost = 0.02f;  // cheap triangles: large leaves
    ObjectBvh with_rows = build_object_bvh(make_tree({}), settings);
    ASSERT_FALSE(with_rows.leaf_rows.empty());
    ObjectBvh corners_only = with_rows;
    corners_only.leaf_rows.clear();
    std::uint32_t largest_leaf = 0;
    for (const NodeWithBox& node : every_node(with_rows))
        if (node.ref.is_leaf()) largest_leaf = std::max(largest_leaf, node.ref.prim_count());
    ASSERT_GT(largest_leaf, 8u);
    Random random(11);
    for (int trial = 0; trial < 16; ++trial) {
        const AffineTransform to_world = test::random_transform(random, 50.0f, trial % 2 == 1);
        const Vec3f direction = to_world.transform_vector({0.3f, -1.0f, 0.2f});
        for (const NodeWithBox& node : every_node(with_rows)) {
            if (!node.ref.is_inner()) continue;
            for (float tolerance : {0.0f, 0.01f})
                EXPECT_EQ(
                    vertex_world_bounds(with_rows, node.ref, node.box, to_world, tolerance),
                    vertex_world_bounds(corners_only, node.ref, node.box, to_world, tolerance));
            // Along the object's axes many vertices tie (rings of the trunk, flat leaves):
            // the first of them in leaf order is the one kept.
            for (Vec3f d : {direction, Vec3f{0, 0, 1}, Vec3f{0, -1, 0}, Vec3f{1, 0, 0}}) {
                const VertexSupport rows = vertex_support(with_rows, node.ref, d, 0.0f);
                const VertexSupport plain = vertex_support(corners_only, node.ref, d, 0.0f);
                EXPECT_EQ(rows.value, plain.value);
                EXPECT_EQ(rows.vertex, plain.vertex);
            }
        }
    }
}

TEST(VertexWorldBounds, TighterThanTransformedChildrenUnderRotation) {
    const ObjectBvh bvh = build_object_bvh(make_torus_knot({}));
    const AffineTransform to_world = AffineTransform::rotate(normalize(Vec3f{1, 2, 3}), 0.7f);
    double vertex_area = 0.0, children_area = 0.0;
    for (const NodeWithBox& node : every_node(bvh)) {
        if (!node.ref.is_inner()) continue;
        vertex_area += vertex_world_bounds(bvh, node.ref, node.box, to_world).half_area();
        children_area += bref_world_bounds(bvh, node.ref, node.box, to_world,
                                           BRefBoundsRule::transformed_children)
                             .half_area();
    }
    EXPECT_LT(vertex_area, 0.95 * children_area);
}

TEST(VertexWorldBounds, EmptyNodeGivesEmptyBox) {
    const ObjectBvh bvh = build_object_bvh(make_box());
    EXPECT_TRUE(vertex_world_bounds(bvh, NodeRef::empty(), bvh.bounds, AffineTransform::identity())
                    .is_empty());
}

}  // namespace
}  // namespace rebraid
