// How the flat structure's leaf rows name a hit's instance and primID (FlatHitIds).
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>

#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/flat_hit_ids.h"
#include "support/reachability.h"
#include "support/test_scenes.h"

namespace rebraid {
namespace {

TEST(FlatHitIds, PacksWhereTheLargestInstanceAndPrimFitOneWord) {
    const FlatHitIds one = FlatHitIds::for_scene(1, 1);
    EXPECT_TRUE(one.packs);
    EXPECT_EQ(one.prim_bits, 0u);
    EXPECT_EQ(one.pack(0, 0), 0u);

    const FlatHitIds forest = FlatHitIds::for_scene(4000, 2560);  // 12 + 12 bits
    EXPECT_TRUE(forest.packs);
    EXPECT_EQ(forest.prim_bits, 12u);

    // 20 bits of instances and 12 of primIDs fill the word; one instance more does not fit.
    const FlatHitIds full = FlatHitIds::for_scene(std::size_t(1) << 20, std::size_t(1) << 12);
    ASSERT_TRUE(full.packs);
    const std::uint32_t word = full.pack((1u << 20) - 1, (1u << 12) - 1);
    EXPECT_EQ(word, 0xffffffffu);
    EXPECT_EQ(full.instance_of(word), (1u << 20) - 1);
    EXPECT_EQ(full.prim_of(word), (1u << 12) - 1);
    EXPECT_EQ(full.instance_of(full.pack(5, 7)), 5u);
    EXPECT_EQ(full.prim_of(full.pack(5, 7)), 7u);
    EXPECT_FALSE(FlatHitIds::for_scene((std::size_t(1) << 20) + 1, std::size_t(1) << 12).packs);

    // A mesh of more than 2^31 triangles leaves no bit for instances.
    EXPECT_FALSE(FlatHitIds::for_scene(1, (std::size_t(1) << 32) + 1).packs);
}

/// The id row of every leaf of `accel` names its triangles as the tables do.
void expect_rows_name_the_tables_ids(const FlatAccel& accel) {
    const ObjectBvh& bvh = accel.bvh();
    ASSERT_FALSE(bvh.leaf_rows.empty());
    const FlatHitIds& ids = accel.hit_ids();
    ASSERT_TRUE(ids.packs);
    const float* rows = bvh.leaf_rows.data() + kLeafRowPadding;
    std::size_t checked = 0;
    test::for_each_leaf(bvh.nodes, bvh.root, [&](NodeRef leaf) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        const float* id_row = leaf_rows_at(rows, first) + kCornerRows * count;
        for (std::uint32_t i = 0; i < count; ++i) {
            const auto word = std::bit_cast<std::uint32_t>(id_row[i]);
            EXPECT_EQ(ids.instance_of(word), accel.triangle_instances()[first + i]);
            EXPECT_EQ(ids.prim_of(word), accel.triangle_prims()[first + i]);
            ++checked;
        }
    });
    EXPECT_EQ(checked, accel.triangle_prims().size());
}

TEST(FlatHitIds, LeafRowsNameEachTrianglesInstanceAndPrim) {
    expect_rows_name_the_tables_ids(FlatAccel(make_default_scene()));
    for (const test::NamedScene& named : test::generated_scenes()) {
        SCOPED_TRACE(named.name);
        expect_rows_name_the_tables_ids(FlatAccel(named.scene));
    }
}

}  // namespace
}  // namespace rebraid
