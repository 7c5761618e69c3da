// World-space boxes of BRefs (rebraid/rebraiding/bref_bounds.h): both rules bound every triangle
// below the node; the children rule is never looser than the paper's transformed box.
#include "rebraid/rebraiding/bref_bounds.h"
#include "rebraid/bvh/object_bvh_builder.h"

#include <gtest/gtest.h>

#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/generators/mesh_generators.h"
#include "support/placed_vertices.h"

namespace rebraid {
namespace {

/// Every node reference of `bvh` below (and including) `ref`, with its object-space box.
void collect(const ObjectBvh& bvh, NodeRef ref, const BBox3f& box,
             std::vector<std::pair<NodeRef, BBox3f>>& out) {
    out.push_back({ref, box});
    if (!ref.is_inner()) return;
    const WideNode& node = bvh.nodes[ref.node_id()];
    for (int c = 0; c < kBvhWidth && !node.children[c].is_empty(); ++c)
        collect(bvh, node.children[c], node.child_bounds(c), out);
}

TEST(BRefBounds, BothRulesBoundTheTrianglesAndChildrenIsTighter) {
    const ObjectBvh bvh = build_object_bvh(make_torus_knot());
    const AffineTransform to_world = AffineTransform::translate({5, -2, 1}) *
                                     AffineTransform::rotate(normalize(Vec3f{1, 2, 3}), 0.7f) *
                                     AffineTransform::scale({3, 0.5f, 1});
    std::vector<std::pair<NodeRef, BBox3f>> nodes;
    collect(bvh, bvh.root, bvh.bounds, nodes);
    ASSERT_GT(nodes.size(), 20u);
    float box_area = 0, children_area = 0;
    for (const auto& [ref, box] : nodes) {
        const BBox3f exact = test::placed_vertex_bounds(bvh, ref, to_world);
        const BBox3f paper =
            bref_world_bounds(bvh, ref, box, to_world, BRefBoundsRule::transformed_box);
        const BBox3f tight =
            bref_world_bounds(bvh, ref, box, to_world, BRefBoundsRule::transformed_children);
        // Contains the box of the transformed corners, exactly: the world box test must never
        // cull a corner the object-space test can hit.
        EXPECT_TRUE(merge(paper, exact) == paper);
        EXPECT_TRUE(merge(tight, exact) == tight);
        // Never looser than the paper's box (beyond the leaves' few-ulp padding).
        EXPECT_LE(tight.half_area(), paper.half_area() * (1 + 1e-5f));
        box_area += paper.half_area();
        children_area += tight.half_area();
    }
    EXPECT_LT(children_area, 0.9f * box_area);  // rotation: a real gain, not a tie
}

TEST(BRefBounds, IdentityTransformGivesTheNodeBox) {
    const ObjectBvh bvh = build_object_bvh(make_torus());
    for (BRefBoundsRule rule :
         {BRefBoundsRule::transformed_box, BRefBoundsRule::transformed_children})
        EXPECT_EQ(bref_world_bounds(bvh, bvh.root, bvh.bounds, AffineTransform::identity(), rule),
                  bvh.bounds);
}

TEST(BRefBounds, VertexRuleUnderABoxPreservingMapIsTheTransformedBox) {
    // A mirror, an axis permutation and a scale: the transformed node box is the box of the
    // mapped vertices, which the vertex rule then gives without a search.
    const ObjectBvh bvh = build_object_bvh(make_torus_knot());
    const AffineTransform to_world{{0, 0, -2}, {3, 0, 0}, {0, 0.5f, 0}, {5, -2, 1}};
    ASSERT_TRUE(to_world.maps_boxes_to_boxes());
    std::vector<std::pair<NodeRef, BBox3f>> nodes;
    collect(bvh, bvh.root, bvh.bounds, nodes);
    ASSERT_GT(nodes.size(), 20u);
    for (const auto& [ref, box] : nodes) {
        const BBox3f exact = test::placed_vertex_bounds(bvh, ref, to_world);
        const BBox3f vertices =
            bref_world_bounds(bvh, ref, box, to_world, BRefBoundsRule::transformed_vertices);
        EXPECT_EQ(vertices,
                  bref_world_bounds(bvh, ref, box, to_world, BRefBoundsRule::transformed_box));
        EXPECT_TRUE(merge(vertices, exact) == vertices);  // holds every mapped vertex
        // and is their box to within the rounding pad (a few ulps of the coordinates).
        EXPECT_LE(test::largest_gap(vertices, exact), 1e-4f);
    }
}

}  // namespace
}  // namespace rebraid
