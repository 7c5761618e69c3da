// The merge of items into the traced top level (merged_top_level.h), world-space items and
// items of placed instances: where each subtree hangs and what it holds, when it is made, and
// that rays find what they found by entering the items. Its hits against Embree's flat scene are
// checked in accel_equivalence_test.cpp ("objects in world space", merged as the first test here
// shows).
#include "rebraid/top_level/merged_top_level.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include "rebraid/bvh/leaf_row_hints.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/core/structure_hash.h"
#include "rebraid/generators/world_space_objects.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/containment.h"
#include "support/entered_hits.h"
#include "support/test_rays.h"
#include "support/test_scenes.h"
#include "support/thread_count_hash.h"

namespace rebraid {
namespace {

/// Index of the ground quad with_small_meshes adds (its only instance's id too).
constexpr std::uint32_t kNoGround = ~0u;

/// `scene` with `count` meshes of four small triangles each (each object BVH one leaf, so
/// their items name leaves) scattered through its bounds, placed by the identity or, with
/// `placed`, by random transforms; and, unless placed, a ground quad under everything (a leaf
/// that spans its top-level node). Returns the ground's instance id in `ground`.
Scene with_small_meshes(Scene scene, std::uint32_t count, bool placed, std::uint32_t* ground) {
    const BBox3f bounds = scene.bounds();
    Random random(17);
    for (std::uint32_t i = 0; i < count; ++i) {
        Mesh mesh = test::make_triangle_soup(4, 100 + i, 0.1f);
        AffineTransform place = test::random_transform(random, 2.0f, true);
        if (!placed) {
            const Vec3f at{random.next_float(bounds.min.x, bounds.max.x),
                           random.next_float(bounds.min.y, bounds.max.y),
                           random.next_float(bounds.min.z, bounds.max.z)};
            for (Vec3f& position : mesh.positions) position = position + at;
            place = AffineTransform::identity();
        }
        scene.meshes.push_back(std::move(mesh));
        scene.instances.push_back({MeshId(scene.meshes.size() - 1), place});
    }
    if (ground != nullptr) *ground = kNoGround;
    if (placed) return scene;
    // Ten times as wide as the rest, so that it takes most of its node's area.
    Mesh quad;
    const float y = bounds.min.y - 0.01f;
    const Vec3f centre = bounds.center(), reach = (bounds.max - bounds.min) * 5.0f;
    quad.positions = {{centre.x - reach.x, y, centre.z - reach.z},
                      {centre.x + reach.x, y, centre.z - reach.z},
                      {centre.x + reach.x, y, centre.z + reach.z},
                      {centre.x - reach.x, y, centre.z + reach.z}};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(std::move(quad));
    scene.instances.push_back({MeshId(scene.meshes.size() - 1), AffineTransform::identity()});
    if (ground != nullptr) *ground = std::uint32_t(scene.instances.size() - 1);
    return scene;
}

Scene world_space_scene(std::uint32_t* ground = nullptr) {
    return with_small_meshes(bake_instances_into_world_space(test::make_overlap_scene(24, 5)), 40,
                             false, ground);
}

InstancedAccel rebraided(
    const Scene& scene, bool merge, bool merge_placed = false, float placed_node_budget = 100.0f,
    float items_out_of_line_area_share = RebraidSettings{}.merge_items_out_of_line_area_share) {
    RebraidSettings settings;
    settings.merge_world_space = merge;
    settings.merge_placed_instances = merge_placed;
    settings.merge_placed_node_budget = placed_node_budget;
    settings.merge_items_out_of_line_area_share = items_out_of_line_area_share;
    return build_rebraid_accel(scene, own_object_bvh_builder(), settings);
}

/// Whether some top-level item is left in the merged tree.
bool keeps_items(const MergedTopLevel& merged) {
    for (std::uint32_t n = 0; n < merged.first_object_node; ++n)
        for (int slot = 0; slot < kBvhWidth; ++slot)
            if (MergedTopLevel::holds_item(merged.nodes[n], slot)) return true;
    return false;
}

/// Placed instances, overlapping: their items are merged only with merge_placed_instances.
Scene placed_scene() {
    return with_small_meshes(test::make_overlap_scene(24, 5), 40, true, nullptr);
}

/// Whether some merged subtree is of a placed instance (its triangles in object space).
bool has_placed_source(const MergedTopLevel& merged) {
    return std::ranges::any_of(merged.sources, [](const MergedLeafSource& source) {
        return source.space != InstanceTarget::kWorldSpace;
    });
}

/// Child `slot`'s box in `a` and `b` have the same bits.
bool same_child_box(const WideNode& a, const WideNode& b, int slot) {
    const BBox3f box_a = a.child_bounds(slot), box_b = b.child_bounds(slot);
    return std::memcmp(&box_a, &box_b, sizeof(BBox3f)) == 0;
}

/// Checks copied node `copy`'s hint words against those of `original`, the object node it
/// copies (MergedTopLevel::kSourceWordFlag): leaf and empty slots name `source`; inner slots
/// keep their hints, but where every slot is inner, one of them, whose hint asked for the
/// fewest lines, names `source` instead.
void expect_hint_words(const WideNode& original, const WideNode& copy, std::uint32_t source) {
    const std::uint32_t source_word = MergedTopLevel::kSourceWordFlag | source;
    int inner_slots = 0, given_up = -1;
    for (int slot = 0; slot < kBvhWidth; ++slot) {
        const std::uint32_t word = copy.leaf_row_hints[slot];
        if (!original.children[slot].is_inner()) {
            EXPECT_EQ(word, source_word) << slot;
            continue;
        }
        ++inner_slots;
        if (word == original.leaf_row_hints[slot]) {
            EXPECT_EQ(word & MergedTopLevel::kSourceWordFlag, 0u) << slot;
            continue;
        }
        EXPECT_EQ(word, source_word) << slot;
        EXPECT_EQ(given_up, -1) << "a second inner slot gave up its hint: " << slot;
        given_up = slot;
    }
    if (inner_slots < kBvhWidth) {
        EXPECT_EQ(given_up, -1);
        return;
    }
    ASSERT_NE(given_up, -1) << "a node of inner children only names no source";
    for (int slot = 0; slot < kBvhWidth; ++slot)
        EXPECT_LE(leaf_row_hint_lines(original.leaf_row_hints[given_up]),
                  leaf_row_hint_lines(original.leaf_row_hints[slot]));
}

/// Checks that the copy below `copy` is the object subtree below `original` node for node
/// (same boxes, same leaves, inner children copied), its leaves taking `source`
/// (source_of_leaves), each copied node reached once (`reached`, indexed by merged node id).
void expect_same_subtree(const MergedTopLevel& merged, const ObjectBvhView& bvh,
                         std::uint32_t source, NodeRef original, NodeRef copy,
                         std::vector<int>& reached) {
    ASSERT_TRUE(copy.is_inner());
    ASSERT_TRUE(merged.is_object_node(copy.node_id()));
    ++reached[copy.node_id()];
    const WideNode& a = bvh.nodes[original.node_id()];
    const WideNode& b = merged.nodes[copy.node_id()];
    expect_hint_words(a, b, source);
    for (int slot = 0; slot < kBvhWidth; ++slot) {
        const NodeRef child = a.children[slot];
        EXPECT_TRUE(same_child_box(a, b, slot));
        if (child.is_inner())
            expect_same_subtree(merged, bvh, source, child, b.children[slot], reached);
        else
            EXPECT_EQ(child, b.children[slot]);
        if (child.is_leaf()) {
            EXPECT_EQ(&merged.source_of_leaves(b, 1u << slot), &merged.sources[source]);
        }
    }
}

/// Checks the leaf hung in slot `slot` of the merged top level's node `node` for `item` (of an
/// instance whose object BVH is `bvh`): the object leaf itself, its hint word naming its
/// instance's source (`source_of`, indexed by instance: one source per instance), the leaves
/// hung in one node all of one instance (`node_instance`), and the leaf's box a small share of
/// its node's. Returns the source.
std::uint32_t expect_hung_leaf(const MergedTopLevel& merged, const WideNode& top_node,
                               std::uint32_t node, int slot, const TopLevelItem& item,
                               const ObjectBvhView& bvh, std::vector<std::uint32_t>& source_of,
                               InstanceId& node_instance) {
    const WideNode& copy = merged.nodes[node];
    EXPECT_EQ(copy.children[slot], item.object_node);
    EXPECT_TRUE(item.object_node.is_leaf());
    const std::uint32_t source = copy.leaf_row_hints[slot] & ~MergedTopLevel::kSourceWordFlag;
    EXPECT_LT(source, merged.sources.size());
    if (source >= merged.sources.size()) return source;
    EXPECT_EQ(&merged.source_of_leaves(copy, 1u << slot), &merged.sources[source]);
    EXPECT_EQ(merged.sources[source].instance, item.instance_id);
    EXPECT_EQ(merged.sources[source].leaf_rows, bvh.leaf_rows);
    EXPECT_EQ(merged.sources[source].triangles, bvh.triangles);
    EXPECT_EQ(merged.sources[source].prim_ids, bvh.prim_ids);
    if (source_of[item.instance_id] == kInvalidId) source_of[item.instance_id] = source;
    EXPECT_EQ(source_of[item.instance_id], source);
    if (node_instance == kInvalidId) node_instance = item.instance_id;
    EXPECT_EQ(node_instance, item.instance_id) << "leaves of two instances hang in one node";
    EXPECT_LE(top_node.child_bounds(slot).half_area(),
              MergedTopLevel::kHungLeafAreaShare * top_node.bounds().half_area());
    return source;
}

TEST(MergedTopLevel, HangsEachWorldSpaceItemsSubtreeOrLeafWhereTheItemWas) {
    std::uint32_t ground = kNoGround;
    const Scene scene = world_space_scene(&ground);
    ASSERT_NE(ground, kNoGround);
    const InstancedAccel accel = rebraided(scene, true);
    const TopLevelBvh& top = accel.top_level();
    const MergedTopLevel& merged = accel.merged_top_level();
    ASSERT_FALSE(merged.empty());
    EXPECT_EQ(merged.root, top.root);
    ASSERT_EQ(merged.first_object_node, top.nodes.size());
    std::vector<int> reached(merged.nodes.size(), 0);
    std::vector<std::uint32_t> hung_source_of(scene.instances.size(), kInvalidId);
    std::size_t merged_items = 0, hung_leaves = 0, kept_items = 0;
    bool ground_kept = false;
    for (std::uint32_t n = 0; n < top.nodes.size(); ++n) {
        InstanceId node_instance = kInvalidId;
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef child = top.nodes[n].children[slot];
            const NodeRef copy = merged.nodes[n].children[slot];
            const bool is_hung =
                (merged.nodes[n].leaf_row_hints[slot] & MergedTopLevel::kSourceWordFlag) != 0;
            EXPECT_TRUE(same_child_box(top.nodes[n], merged.nodes[n], slot));
            if (!child.is_leaf() || (copy == child && !is_hung)) {
                EXPECT_EQ(copy, child);
                EXPECT_EQ(merged.nodes[n].leaf_row_hints[slot], top.nodes[n].leaf_row_hints[slot]);
                if (child.is_leaf()) {
                    ++kept_items;
                    ground_kept =
                        ground_kept || top.items[child.first_prim()].instance_id == ground;
                }
                continue;
            }
            ASSERT_EQ(child.prim_count(), 1u);
            const TopLevelItem& item = top.items[child.first_prim()];
            const InstanceTarget& target = accel.instance_targets()[item.instance_id];
            EXPECT_EQ(target.space, InstanceTarget::kWorldSpace);
            const ObjectBvhView& bvh = accel.object_views()[target.mesh];
            if (is_hung) {
                // A world-space item naming an object leaf: the leaf hangs in its place, its
                // source after every copied subtree's.
                EXPECT_GE(expect_hung_leaf(merged, top.nodes[n], n, slot, item, bvh, hung_source_of,
                                           node_instance),
                          merged_items);
                ++hung_leaves;
                continue;
            }
            // A world-space item naming an inner object node: its subtree copied.
            ASSERT_TRUE(item.object_node.is_inner());
            // Sources follow the merged slots in the top level's node and slot order.
            const std::uint32_t source = std::uint32_t(merged_items);
            ASSERT_LT(source, merged.sources.size());
            EXPECT_EQ(merged.sources[source].instance, item.instance_id);
            EXPECT_EQ(merged.sources[source].leaf_rows, bvh.leaf_rows);
            EXPECT_EQ(merged.sources[source].triangles, bvh.triangles);
            EXPECT_EQ(merged.sources[source].prim_ids, bvh.prim_ids);
            expect_same_subtree(merged, bvh, source, item.object_node, copy, reached);
            ++merged_items;
        }
    }
    EXPECT_GT(hung_leaves, 0u);
    EXPECT_GT(merged_items, 0u);
    const auto hung_instances =
        std::size_t(std::ranges::count_if(hung_source_of, [](auto s) { return s != kInvalidId; }));
    EXPECT_EQ(merged_items + hung_instances, merged.sources.size());
    EXPECT_EQ(merged_items + hung_leaves + kept_items, top.items.size());
    // The ground quad spans the nodes above it: a leaf that nearly every ray through its node
    // enters stays an item (MergedTopLevel::kHungLeafAreaShare).
    EXPECT_TRUE(ground_kept);
    // Every copied node below exactly one merged slot, the top level's own below none.
    for (std::size_t id = 0; id < reached.size(); ++id)
        EXPECT_EQ(reached[id], merged.is_object_node(std::uint32_t(id)) ? 1 : 0) << id;
}

/// Whether some merged subtree or hung leaf is of an instance in world space.
bool has_world_space_source(const MergedTopLevel& merged) {
    return std::ranges::any_of(merged.sources, [](const MergedLeafSource& source) {
        return source.space == InstanceTarget::kWorldSpace;
    });
}

// World-space items merge where they are most of the items, or where the placed items merge
// too (then the world-space ones would be the only entries left).
TEST(MergedTopLevel, MergesWorldSpaceItemsWhereMostAreOrWherePlacedItemsMerge) {
    Scene mixed = test::make_overlap_scene(24, 5);
    for (std::size_t i = 0; i < mixed.instances.size(); i += 3)
        mixed.instances[i].object_to_world = AffineTransform::identity();
    EXPECT_TRUE(rebraided(mixed, true).merged_top_level().empty());
    EXPECT_TRUE(rebraided(test::make_overlap_scene(24, 5), true).merged_top_level().empty());
    EXPECT_FALSE(rebraided(world_space_scene(), true).merged_top_level().empty());
    EXPECT_TRUE(rebraided(world_space_scene(), false).merged_top_level().empty());

    const InstancedAccel all = rebraided(mixed, true, true, 100.0f);
    EXPECT_TRUE(has_world_space_source(all.merged_top_level()));
    EXPECT_TRUE(has_placed_source(all.merged_top_level()));
    EXPECT_FALSE(keeps_items(all.merged_top_level()));
    // Placed items over their budget: the world-space minority is not merged either.
    EXPECT_FALSE(has_world_space_source(rebraided(mixed, true, true, 0.0f).merged_top_level()));
    // Nor where world-space items are not to be merged at all.
    EXPECT_FALSE(has_world_space_source(rebraided(mixed, false, true, 100.0f).merged_top_level()));
}

/// Checks the copy below `copy` of the object subtree below `original` of a placed instance's
/// `bvh`: the same leaves and shape, each child's box in world space, holding the corners
/// of the child's triangles mapped by `to_world`, and its leaves taking `source`.
void expect_world_boxed_subtree(const MergedTopLevel& merged, const ObjectBvhView& bvh,
                                const std::vector<bool>& cut, const AffineTransform& to_world,
                                std::uint32_t source, NodeRef original, NodeRef copy,
                                std::vector<int>& reached) {
    ASSERT_TRUE(copy.is_inner());
    ASSERT_TRUE(merged.is_object_node(copy.node_id()));
    ++reached[copy.node_id()];
    const WideNode& a = bvh.nodes[original.node_id()];
    const WideNode& b = merged.nodes[copy.node_id()];
    expect_hint_words(a, b, source);
    for (int slot = 0; slot < kBvhWidth; ++slot) {
        const NodeRef child = a.children[slot];
        if (child.is_empty()) {
            EXPECT_TRUE(b.children[slot].is_empty());
            continue;
        }
        const BBox3f box = b.child_bounds(slot);
        std::vector<NodeRef> below{child};  // the leaves under this child
        while (!below.empty()) {
            const NodeRef ref = below.back();
            below.pop_back();
            if (ref.is_inner()) {
                for (const NodeRef grandchild : bvh.nodes[ref.node_id()].children)
                    if (!grandchild.is_empty()) below.push_back(grandchild);
                continue;
            }
            for (std::uint32_t i = ref.first_prim(); i < ref.first_prim() + ref.prim_count(); ++i) {
                // A triangle cut by spatial splits is boxed only where its part lies.
                if (cut[bvh.prim_ids[i]]) continue;
                for (const Vec3f& corner :
                     {bvh.triangles[i].v0, bvh.triangles[i].v1, bvh.triangles[i].v2}) {
                    const Vec3f world = to_world.transform_point(corner);
                    for (int axis = 0; axis < 3; ++axis) {
                        EXPECT_LE(box.min[axis], world[axis]);
                        EXPECT_GE(box.max[axis], world[axis]);
                    }
                }
            }
        }
        if (child.is_inner()) {
            expect_world_boxed_subtree(merged, bvh, cut, to_world, source, child, b.children[slot],
                                       reached);
        } else {
            EXPECT_EQ(child, b.children[slot]);
            EXPECT_EQ(&merged.source_of_leaves(b, 1u << slot), &merged.sources[source]);
        }
    }
}

TEST(MergedTopLevel, HangsPlacedItemsSubtreesInWorldBoxes) {
    const Scene scene = placed_scene();
    const InstancedAccel accel = rebraided(scene, true, true);
    const TopLevelBvh& top = accel.top_level();
    const MergedTopLevel& merged = accel.merged_top_level();
    ASSERT_FALSE(merged.empty());
    EXPECT_TRUE(has_placed_source(merged));
    std::vector<int> reached(merged.nodes.size(), 0);
    std::size_t merged_items = 0, hung_leaves = 0, world_space_items = 0, placed_items = 0;
    for (std::uint32_t n = 0; n < top.nodes.size(); ++n)
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef child = top.nodes[n].children[slot];
            const NodeRef copy = merged.nodes[n].children[slot];
            EXPECT_TRUE(same_child_box(top.nodes[n], merged.nodes[n], slot));
            const bool is_hung =
                (merged.nodes[n].leaf_row_hints[slot] & MergedTopLevel::kSourceWordFlag) != 0;
            if (!child.is_leaf() || (copy == child && !is_hung)) continue;
            const TopLevelItem& item = top.items[child.first_prim()];
            const InstanceTarget& target = accel.instance_targets()[item.instance_id];
            // The world-space items merge with the placed ones (their meshes built in world
            // space: the identity maps their corners).
            const bool is_world_space = target.space == InstanceTarget::kWorldSpace;
            if (is_hung) {
                // An item naming an object leaf hangs in its slot: its box stays the item's
                // (world space), its triangles in their object space.
                EXPECT_EQ(copy, item.object_node);
                const MergedLeafSource& source =
                    merged.source_of_leaves(merged.nodes[n], 1u << slot);
                EXPECT_EQ(source.instance, item.instance_id);
                EXPECT_EQ(source.space, target.space);
                ++hung_leaves;
                continue;
            }
            ASSERT_LT(merged_items, merged.sources.size());
            const MergedLeafSource& source = merged.sources[merged_items];
            EXPECT_EQ(source.instance, item.instance_id);
            EXPECT_EQ(source.target, &target);
            EXPECT_EQ(source.space, target.space);
            expect_world_boxed_subtree(
                merged, accel.object_views()[target.mesh],
                test::cut_triangles(accel.object_bvhs()[target.mesh]),
                is_world_space ? AffineTransform::identity()
                               : scene.instances[item.instance_id].object_to_world,
                std::uint32_t(merged_items), item.object_node, copy, reached);
            ++merged_items;
            ++(is_world_space ? world_space_items : placed_items);
        }
    EXPECT_GT(hung_leaves, 0u);
    EXPECT_GT(world_space_items, 0u);
    EXPECT_GT(placed_items, 0u);
    EXPECT_LE(merged_items, merged.sources.size());
    for (std::size_t id = 0; id < reached.size(); ++id)
        EXPECT_EQ(reached[id], merged.is_object_node(std::uint32_t(id)) ? 1 : 0) << id;
}

// The budget bounds the copied nodes; hung leaves copy none, so they hang whatever it is.
TEST(MergedTopLevel, MergesPlacedItemsOnlyWhenAskedAndWithinTheirBudget) {
    EXPECT_TRUE(rebraided(placed_scene(), true, false).merged_top_level().empty());
    const InstancedAccel none_copied = rebraided(placed_scene(), true, true, 0.0f);
    const MergedTopLevel& leaves_only = none_copied.merged_top_level();
    ASSERT_FALSE(leaves_only.empty());
    EXPECT_EQ(leaves_only.nodes.size(), leaves_only.first_object_node);
    EXPECT_GT(rebraided(placed_scene(), true, true, 100.0f).merged_top_level().nodes.size(),
              leaves_only.first_object_node);
}

// Copied nodes ask for their children's rows where the structure's rows outgrow the caches,
// as its object BVHs' traversals do (ObjectBvhView::prefetches_rows), and nowhere else.
TEST(MergedTopLevel, AsksForRowsAheadWhereItsObjectBvhsDo) {
    const Scene scene = world_space_scene();
    const InstancedAccel accel = rebraided(scene, true);
    const MergedTopLevel& small = accel.merged_top_level();
    ASSERT_FALSE(small.empty());
    ASSERT_FALSE(accel.object_views().front().prefetches_rows);
    EXPECT_EQ(small.rows_prefetch_from, NodeRef::kEmptyBits);

    std::vector<ObjectBvhView> views = accel.object_views();
    for (ObjectBvhView& view : views) view.prefetches_rows = true;
    std::vector<AffineTransform> object_to_world;
    for (const Instance& instance : scene.instances)
        object_to_world.push_back(instance.object_to_world);
    // (The node count only sizes the placed items' budget: none are placed here.)
    const MergedTopLevel large = merge_top_level_items(accel.top_level(), accel.instance_targets(),
                                                       views, object_to_world, 0);
    ASSERT_FALSE(large.empty());
    EXPECT_EQ(large.rows_prefetch_from, large.first_object_node);
    EXPECT_EQ(large.nodes.size(), small.nodes.size());
}

TEST(MergedTopLevel, EntersItemsOutOfLineWhereTheirAreasAddUpToLittle) {
    std::uint32_t ground = kNoGround;
    const Scene scene = world_space_scene(&ground);
    // The ground quad stays an item (it spans its node) and its box is about the root's.
    const InstancedAccel by_default = rebraided(scene, true);
    ASSERT_TRUE(keeps_items(by_default.merged_top_level()));
    EXPECT_FALSE(by_default.merged_top_level().enters_items_out_of_line);
    EXPECT_FALSE(
        rebraided(scene, true, false, 100.0f, 0.0f).merged_top_level().enters_items_out_of_line);
    EXPECT_TRUE(
        rebraided(scene, true, false, 100.0f, 1e6f).merged_top_level().enters_items_out_of_line);
    // Without the ground, what is left is small items: out of line by default.
    Scene small = scene;
    ASSERT_EQ(ground, small.instances.size() - 1);
    small.instances.pop_back();
    small.meshes.pop_back();
    const InstancedAccel without_ground = rebraided(small, true);
    ASSERT_TRUE(keeps_items(without_ground.merged_top_level()));
    EXPECT_TRUE(without_ground.merged_top_level().enters_items_out_of_line);
}

/// Placed items merged or not, and the items left entered out of line or in the loop.
class MergedRays : public ::testing::TestWithParam<std::tuple<bool, bool>> {};

TEST_P(MergedRays, FindWhatEnteringTheItemsFinds) {
    const auto [placed, out_of_line] = GetParam();
    const Scene scene = placed ? placed_scene() : world_space_scene();
    InstancedAccel merged = rebraided(scene, true, placed, 100.0f, out_of_line ? 1e6f : 0.0f);
    InstancedAccel entered = rebraided(scene, false);
    ASSERT_FALSE(merged.merged_top_level().empty());
    EXPECT_EQ(has_placed_source(merged.merged_top_level()), placed);
    EXPECT_EQ(merged.merged_top_level().enters_items_out_of_line,
              out_of_line || !keeps_items(merged.merged_top_level()));
    // The world-space scene keeps items (the ground, leaves not hung), so both forms of
    // entering them are traced.
    if (!placed) {
        EXPECT_TRUE(keeps_items(merged.merged_top_level()));
    }
    // The same world ray meets the same triangles with the same arithmetic.
    test::expect_hits_as_entering(merged, entered,
                                  test::varied_rays(entered, scene.bounds(), 10000, 7), true);
}

TEST_P(MergedRays, SameCopyOnAnyThreadCount) {
    // Plain variables, not structured bindings: the lambda below captures them.
    const bool placed = std::get<0>(GetParam()), out_of_line = std::get<1>(GetParam());
    const Scene scene = placed ? placed_scene() : world_space_scene();
    test::expect_same_hash_on_threads({1, 2, 8}, [&] {
        const InstancedAccel accel =
            rebraided(scene, true, placed, 100.0f, out_of_line ? 1e6f : 0.0f);
        const MergedTopLevel& merged = accel.merged_top_level();
        StructureHash hash;
        hash.add_value(merged.enters_items_out_of_line);
        hash.add<WideNode>(merged.nodes);
        for (const MergedLeafSource& source : merged.sources) hash.add_value(source.instance);
        return hash.value();
    });
}

INSTANTIATE_TEST_SUITE_P(MergedTopLevel, MergedRays,
                         ::testing::Combine(::testing::Bool(), ::testing::Bool()),
                         [](const auto& info) {
                             return std::string(std::get<0>(info.param) ? "PlacedItems"
                                                                        : "WorldSpaceItems") +
                                    (std::get<1>(info.param) ? "OutOfLine" : "InTheLoop");
                         });

}  // namespace
}  // namespace rebraid
