// Support tables: world boxes of a mesh's placed vertices from values computed once per
// mesh, against a pass over every vertex.
#include "rebraid/bvh/support_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/object_support_tables.h"
#include "rebraid/core/random.h"
#include "rebraid/generators/mesh_generators.h"
#include "support/placed_vertices.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

struct NamedMesh {
    std::string name;
    Mesh mesh;
};

/// Round, elongated, boxy, flat and scattered shapes.
std::vector<NamedMesh> test_meshes() {
    Mesh flat = make_ground_grid({});
    return {{"sphere", make_uv_sphere({})},   {"torus knot", make_torus_knot({})},
            {"tree", make_tree({})},          {"box", make_box({3.0f, 0.2f, 1.0f})},
            {"ground grid", std::move(flat)}, {"soup", test::make_triangle_soup(300, 5)}};
}

/// The root's table under rotated, scaled, mirrored and translated placements holds every
/// placed vertex. With its searches (world_bounds) each face lies within 1 % (the default
/// tolerance) of the node's extent of their box, as vertex_world_bounds does; from the table
/// alone (table_world_bounds) within the grid's error: at most 2.7 % on these shapes, 5 %
/// asserted.
TEST(SupportTable, HoldsEveryPlacedVertexWithinItsTolerance) {
    Random random(11);
    for (const NamedMesh& named : test_meshes()) {
        const ObjectBvh bvh = build_object_bvh(named.mesh);
        const SupportTable table(bvh, bvh.root, bvh.bounds);
        for (int trial = 0; trial < 40; ++trial) {
            SCOPED_TRACE(named.name + ", trial " + std::to_string(trial));
            const AffineTransform to_world = test::random_transform(random, 50.0f, trial % 2 == 1);
            const BBox3f reference = test::placed_vertex_bounds(bvh, bvh.root, to_world);
            // The node's transformed box bounds its extent along every row of the transform.
            const Vec3f extent = to_world.transform_bbox(bvh.bounds).extent();
            const float largest_extent = std::max({extent.x, extent.y, extent.z});
            const BBox3f searched = table.world_bounds(to_world, bvh, bvh.root);
            ASSERT_TRUE(searched.contains(reference));
            EXPECT_LE(test::largest_gap(searched, reference), 0.01f * largest_extent + 1e-4f);
            const BBox3f table_alone = table.table_world_bounds(to_world);
            ASSERT_TRUE(table_alone.contains(reference));
            EXPECT_LE(test::largest_gap(table_alone, reference), 0.05f * largest_extent + 1e-4f);
        }
    }
}

/// Far from the origin the rounding of the mapped centre and of the sums must still be
/// covered: a small object translated by 10^6 and one made of large coordinates.
TEST(SupportTable, HoldsEveryVertexFarFromTheOrigin) {
    Random random(3);
    Mesh far_mesh = make_torus_knot({});
    for (Vec3f& p : far_mesh.positions) p = p * 10.0f + Vec3f{4e5f, -3e5f, 2e5f};
    for (const Mesh& mesh : {make_uv_sphere({}), far_mesh}) {
        const ObjectBvh bvh = build_object_bvh(mesh);
        const SupportTable table(bvh, bvh.root, bvh.bounds);
        for (int trial = 0; trial < 20; ++trial) {
            const AffineTransform to_world = AffineTransform::translate({1e6f, -2e6f, 5e5f}) *
                                             test::random_transform(random, 10.0f, trial % 2 == 1);
            EXPECT_TRUE(table.world_bounds(to_world, bvh, bvh.root)
                            .contains(test::placed_vertex_bounds(bvh, bvh.root, to_world)))
                << "trial " << trial;
            EXPECT_TRUE(table.table_world_bounds(to_world).contains(
                test::placed_vertex_bounds(bvh, bvh.root, to_world)))
                << "trial " << trial;
        }
    }
}

/// Every grid direction is exact (up to the search tolerance), so a placement that maps the
/// object's axes onto the world's (a permutation with scales) gives the box of the vertices.
TEST(SupportTable, AxisAlignedPlacementGivesTheVertexBox) {
    const ObjectBvh bvh = build_object_bvh(make_torus_knot({}));
    const SupportTable table(bvh, bvh.root, bvh.bounds, 0.0f);
    const AffineTransform swap_and_scale{{0, 2, 0}, {0, 0, -3}, {0.5f, 0, 0}, {1, 2, 3}};
    const BBox3f reference = test::placed_vertex_bounds(bvh, bvh.root, swap_and_scale);
    const BBox3f bounds = table.world_bounds(swap_and_scale, bvh, bvh.root, 0.0f);
    ASSERT_TRUE(bounds.contains(reference));
    const Vec3f extent = reference.extent();
    EXPECT_LE(test::largest_gap(bounds, reference),
              1e-5f * std::max({extent.x, extent.y, extent.z}));
}

TEST(SupportTable, EmptyNodeGivesEmptyBox) {
    const ObjectBvh bvh = build_object_bvh(make_box());
    const AffineTransform identity = AffineTransform::identity();
    EXPECT_TRUE(SupportTable().world_bounds(identity, bvh, bvh.root).is_empty());
    EXPECT_TRUE(SupportTable(bvh, NodeRef::empty(), bvh.bounds)
                    .world_bounds(identity, bvh, NodeRef::empty())
                    .is_empty());
}

/// The tables of a BVH's top: its root and each inner child of the root, nothing else; each
/// holds its node's placed vertices.
TEST(ObjectSupportTables, CoverTheRootAndItsInnerChildren) {
    const ObjectBvh bvh = build_object_bvh(make_tree({}));
    ASSERT_TRUE(bvh.root.is_inner());
    const ObjectSupportTables tables(bvh);
    const AffineTransform to_world = AffineTransform::rotate(normalize(Vec3f{1, 2, 3}), 0.7f);
    ASSERT_NE(tables.find(bvh.root), nullptr);
    const WideNode& root = bvh.nodes[bvh.root.node_id()];
    int inner_children = 0;
    for (int c = 0; c < kBvhWidth && !root.children[c].is_empty(); ++c) {
        const NodeRef child = root.children[c];
        const SupportTable* table = tables.find(child);
        if (!child.is_inner()) {
            EXPECT_EQ(table, nullptr);
            continue;
        }
        ++inner_children;
        ASSERT_NE(table, nullptr);
        EXPECT_TRUE(table->world_bounds(to_world, bvh, child)
                        .contains(test::placed_vertex_bounds(bvh, child, to_world)));
        if (!bvh.nodes[child.node_id()].children[0].is_inner()) continue;
        EXPECT_EQ(tables.find(bvh.nodes[child.node_id()].children[0]), nullptr);
    }
    EXPECT_GT(inner_children, 0);
    EXPECT_EQ(ObjectSupportTables().find(bvh.root), nullptr);
}

}  // namespace
}  // namespace rebraid
