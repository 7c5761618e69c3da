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
