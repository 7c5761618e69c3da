#pragma once

// The ray queries of FlatAccel and InstancedAccel, compiled once per kernel level: each
// trace_kernels_<level>.cpp includes this file once, with the compiler targeting its level,
// and the kernel headers then put everything below into that level's inline namespace
// (simd_config.h). Include nowhere else.

#include "rebraid/top_level/trace_kernel_prelude.h"

#include "rebraid/bvh/object_traversal.h"
#include "rebraid/bvh/prepared_ray.h"
#include "rebraid/bvh/root_box_cull.h"
#include "rebraid/bvh/traversal.h"
#include "rebraid/core/simd_config.h"
#include "rebraid/top_level/returned_hit.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

// The entry points are flattened (every call inside them inlined): in one unit with all
// of them, the compiler's unit-growth limits otherwise leave the traversal loops out of line and
// its register allocation worse, 8-15 % more instructions per ray than each query compiled
// alone (callgrind, diffuse rays of fzk_haus and cg57_cruiser).

/// Counts a ray that misses the root box (misses_root_box) as the root node's visit, the box
/// test the root box stands in for.
inline void count_root_visit(TraversalCounters* counters) {
    if (counters) ++counters->nodes_visited;
}

template <TriangleTest kTest>
Hit flat_closest_hit(const FlatAccel& accel, const Ray& ray, TraversalCounters* counters) {
    Hit hit;  // one object every return names: no copy between the returns
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) {
        count_root_visit(counters);
        return hit;
    }
    PreparedRay traversal_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
    // Where the leaf rows name instance and primID in one word (FlatHitIds), the closest hit's
    // word comes from the leaf just tested. Otherwise world triangles are numbered in leaf
    // order, the hit's leaf position indexes the tables, and since that lookup after the
    // traversal would miss the cache on large scenes, each hit's ids are asked for as it is
    // found.
    const FlatHitIds ids = accel.hit_ids();
    const InstanceId* instances = accel.triangle_instances().data();
    const PrimId* prims = accel.triangle_prims().data();
    std::optional<std::uint32_t> hit_word;
    const auto on_closer_hit = [&](std::uint32_t position, auto&&, std::optional<PrimId> row_word) {
        if (ids.packs && row_word) {
            hit_word = *row_word;
            return;
        }
        __builtin_prefetch(instances + position);
        __builtin_prefetch(prims + position);
    };
    const ObjectBvh& bvh = accel.bvh();
    if (intersect_object_bvh_leaf_order<kTest>(bvh, bvh.root, traversal_ray, hit, counters,
                                               on_closer_hit)) {
        if (hit_word) {
            hit.instance_id = ids.instance_of(*hit_word);
            hit.prim_id = ids.prim_of(*hit_word);
        } else {
            const PrimId world_prim = hit.prim_id;
            hit.instance_id = instances[world_prim];
            hit.prim_id = prims[world_prim];
        }
    }
    return hit;
}

template <TriangleTest kTest>
[[gnu::flatten]] Hit flat_intersect(const FlatAccel& accel, const Ray& ray,
                                    TraversalCounters* counters) {
    return returned_hit(flat_closest_hit<kTest>(accel, ray, counters));
}

template <TriangleTest kTest>
[[gnu::flatten]] bool flat_occluded(const FlatAccel& accel, const Ray& ray) {
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) return false;
    PreparedRay traversal_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
    return occluded_object_bvh<kTest>(accel.bvh(), accel.bvh().root, traversal_ray, nullptr);
}

/// `org` and `dir` mapped by `to_object` into an instance's object space. Every query maps
/// rays with this one function, so a ray has the same bits in an object space whichever query
/// mapped it. The SIMD form maps all three axes at once with a fused multiply-add per column,
/// in the order Embree's AVX2 and AVX-512 instance kernels use (x * col_x + (y * col_y +
/// (z * col_z + translation))): with Embree's own world-to-object map
/// (InstancedAccel::set_world_to_object) the mapped ray then has Embree's bits, and so have
/// the Möller test's terms (MollerTerms). The scalar form takes each product and sum on its
/// own.
inline void map_into_object_space(const AffineTransform& to_object, Vec3f org, Vec3f dir,
                                  Vec3f& object_org, Vec3f& object_dir) {
#ifdef REBRAID_SIMD_AVX2
    static_assert(sizeof(AffineTransform) == 12 * sizeof(float), "columns then translation");
    const float* m = &to_object.col_x.x;
    const __m128 col_x = _mm_loadu_ps(m), col_y = _mm_loadu_ps(m + 3), col_z = _mm_loadu_ps(m + 6);
    const __m128 tail = _mm_loadu_ps(m + 8);  // col_z.z, then the translation
    const __m128 translation = _mm_shuffle_ps(tail, tail, _MM_SHUFFLE(3, 3, 2, 1));
    const auto columns = [&](Vec3f v, __m128 z_term) {
        return _mm_fmadd_ps(_mm_set1_ps(v.x), col_x, _mm_fmadd_ps(_mm_set1_ps(v.y), col_y, z_term));
    };
    alignas(16) float mapped_org[4], mapped_dir[4];
    _mm_store_ps(mapped_org, columns(org, _mm_fmadd_ps(_mm_set1_ps(org.z), col_z, translation)));
    _mm_store_ps(mapped_dir, columns(dir, _mm_mul_ps(_mm_set1_ps(dir.z), col_z)));
    object_org = {mapped_org[0], mapped_org[1], mapped_org[2]};
    object_dir = {mapped_dir[0], mapped_dir[1], mapped_dir[2]};
#else
    object_org = to_object.transform_point(org);
    object_dir = to_object.transform_vector(dir);
#endif
}

/// The ray mapped into the object space of the instance a top-level item names, prepared
/// once per run of items in the same space (a re-braided top level holds several items per
/// instance, often side by side in one leaf, and instances placed by the same transform share
/// a space). t is invariant under the affine map, so tnear and tfar carry over unchanged.
/// Instances placed by the identity (objects built in world space, the paper's common case)
/// use the prepared world ray itself: no transform, no reciprocals, no broadcasts, and the
/// same numbers, since the identity maps every finite ray exactly.
class ObjectRayCache {
public:
    explicit ObjectRayCache(PreparedRay& world_ray) : world_ray_(world_ray) {}

    PreparedRay& ray_for(const InstanceTarget& target) {
        if (target.space == InstanceTarget::kWorldSpace) return world_ray_;
        const TraversalRay& world = world_ray_.ray;
        if (target.space != space_) {
            Vec3f org, dir;
            map_into_object_space(target.to_object, world.org, world.dir, org, dir);
            ray_.emplace(org, dir, world.tnear, world.tfar);
            space_ = target.space;
        }
        ray_->ray.tnear = world.tnear;
        ray_->ray.tfar = world.tfar;
        return *ray_;
    }

    /// The ray in `target`'s space for triangle tests alone (the leaves of a merged placed
    /// instance, whose boxes are in world space): the same mapped origin and direction as
    /// ray_for's, without the reciprocals and box-test values only a traversal in that space
    /// reads.
    const TriangleGroupRay& triangle_ray_for(const InstanceTarget& target) {
        if (target.space == InstanceTarget::kWorldSpace) return world_ray_.triangle_ray;
        if (target.space == space_) return ray_->triangle_ray;
        if (target.space != triangle_space_) {
            const TraversalRay& world = world_ray_.ray;
            Vec3f org, dir;
            map_into_object_space(target.to_object, world.org, world.dir, org, dir);
            triangle_ray_.emplace(org, dir);
            triangle_space_ = target.space;
        }
        return *triangle_ray_;
    }

private:
    PreparedRay& world_ray_;
    std::uint32_t space_ = InstanceTarget::kWorldSpace;
    std::optional<PreparedRay> ray_;
    std::uint32_t triangle_space_ = InstanceTarget::kWorldSpace;
    std::optional<TriangleGroupRay> triangle_ray_;
};

/// What a leaf item of `top` may be (StartLeaf): part of a leaf only where opening split leaves.
inline StartLeaf start_leaf_of(const TopLevelBvh& top) {
    return top.has_partial_leaves ? StartLeaf::may_be_part : StartLeaf::whole;
}

/// Tells `observer` (when not null) of each closer hit in `instance`.
inline auto closer_hit_notifier(const CloserHitObserver* observer, InstanceId instance) {
    return [observer, instance](const HitTriangle& triangle) {
        if (observer != nullptr) observer->on_closer_hit(observer->context, instance, triangle);
    };
}

/// Where a query of a top level that is one item starts (a scene of one instance that
/// opening left whole; InstancedAccel takes these queries for such a structure): at the
/// item's object node, with the ray prepared once in the item's space, as ObjectRayCache
/// maps it. No top-level traversal, and no world-space ray unless the instance is placed by
/// the identity, whose space is the world's: the query costs what a flat BVH's does, plus
/// the mapping. The same hits, since the top level's root is then a leaf, whose box no
/// traversal tests. Everything it reads of the structure is in one record (SoleItem).
struct SoleItemStart {
    const SoleItem& item;
    StartLeaf start_leaf;
    std::optional<PreparedRay> ray;

    /// `slab_terms` are those of world_ray.
    SoleItemStart(const InstancedAccel& accel, const Ray& world_ray, const SlabTerms& slab_terms)
        : item(accel.sole_item()), start_leaf(start_leaf_of(accel.top_level())) {
        if (item.target.space == InstanceTarget::kWorldSpace) {
            ray.emplace(world_ray.org, world_ray.dir, world_ray.tnear, world_ray.tfar, slab_terms);
            return;
        }
        Vec3f org, dir;
        map_into_object_space(item.target.to_object, world_ray.org, world_ray.dir, org, dir);
        ray.emplace(org, dir, world_ray.tnear, world_ray.tfar);
    }
};

/// The closest hit of a top level of one item (SoleItemStart); `located` and `observer` as for
/// instanced_closest_hit.
template <TriangleTest kTest>
Hit sole_item_closest_hit(const InstancedAccel& accel, const Ray& ray, TraversalCounters* counters,
                          HitTriangle* located, const CloserHitObserver* observer) {
    Hit hit;  // one object every return names: no copy between the returns
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) {
        // Counted as the query it stands in for: the entry, then its root's box test.
        if (counters) ++counters->object_entries;
        count_root_visit(counters);
        return hit;
    }
    SoleItemStart start(accel, ray, slab_terms);
    if (counters) ++counters->object_entries;
    if (intersect_object_bvh<kTest>(start.item.bvh, start.item.node, *start.ray, hit, counters,
                                    located, closer_hit_notifier(observer, start.item.instance),
                                    start.start_leaf))
        hit.instance_id = start.item.instance;
    return hit;
}

template <TriangleTest kTest>
[[gnu::flatten]] bool sole_item_occluded(const InstancedAccel& accel, const Ray& ray) {
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) return false;
    SoleItemStart start(accel, ray, slab_terms);
    return occluded_object_bvh<kTest>(start.item.bvh, start.item.node, *start.ray, nullptr,
                                      start.start_leaf);
}

/// Prefetches what entering the first item of top-level leaf `leaf` reads first: its object
/// node, or a leaf's triangles in the storage the traversal will read (object_traversal.h).
inline void prefetch_item_target(const TopLevelBvh& top, const InstanceTarget* targets,
                                 const ObjectBvhView* views, NodeRef leaf, StartLeaf start_leaf) {
    const TopLevelItem& item = top.items[leaf.first_prim()];
    const ObjectBvhView& bvh = views[targets[item.instance_id].mesh];
    const NodeRef node = item.object_node;
    if (node.is_inner()) {
        prefetch_node(bvh.nodes, node);
    } else if (rows_serve(bvh, node, start_leaf)) {
        // The cache lines of the leaf's rows.
        const auto first =
            reinterpret_cast<std::uintptr_t>(leaf_rows_at(bvh.leaf_rows, node.first_prim()));
        const std::uintptr_t end =
            first + sizeof(float) * kRowFloatsPerTriangle * node.prim_count();
        for (std::uintptr_t line = first & ~std::uintptr_t(63); line < end; line += 64)
            __builtin_prefetch(reinterpret_cast<const void*>(line));
    } else {
        __builtin_prefetch(bvh.triangles + node.first_prim());
    }
}

/// Enters the items of top-level leaf `leaf` for a closest-hit query: each item takes the
/// ray into its instance's space (ObjectRayCache) and traverses its object BVH from its node;
/// on a closer hit shortens the world ray, sets `hit` (instance and mesh primID) and returns
/// true. `located` and `observer` as for instanced_closest_hit. A function of the query's
/// values rather than a member of ItemEntries: called through ItemEntries from
/// instanced_closest_hit, that query took 0.4-0.7 % more instructions per diffuse ray
/// (callgrind, AVX2, cg57_cruiser and two_cylinder_engine), the compiler keeping fewer of its
/// values in registers.
template <TriangleTest kTest>
bool enter_items_closest(const TopLevelBvh& top, const InstanceTarget* targets,
                         const ObjectBvhView* views, StartLeaf start_leaf, NodeRef leaf,
                         ObjectRayCache& object_rays, PreparedRay& world_ray, Hit& hit,
                         TraversalCounters* counters, HitTriangle* located,
                         const CloserHitObserver* observer) {
    bool found = false;
    const std::uint32_t end = leaf.first_prim() + leaf.prim_count();
    for (std::uint32_t i = leaf.first_prim(); i < end; ++i) {
        const TopLevelItem& item = top.items[i];
        const InstanceTarget& target = targets[item.instance_id];
        if (counters) ++counters->object_entries;
        PreparedRay& object_ray = object_rays.ray_for(target);
        if (intersect_object_bvh<kTest>(
                views[target.mesh], item.object_node, object_ray, hit, counters, located,
                closer_hit_notifier(observer, item.instance_id), start_leaf)) {
            world_ray.ray.tfar = object_ray.ray.tfar;
            hit.instance_id = item.instance_id;
            found = true;
        }
    }
    return found;
}

/// What a query of an instanced structure reads to enter top-level items, and entering them:
/// each item of a top-level leaf takes the ray into its instance's space (ObjectRayCache) and
/// traverses its object BVH from its node.
struct ItemEntries {
    const TopLevelBvh& top;
    const InstanceTarget* targets;
    const ObjectBvhView* views;
    StartLeaf start_leaf;

    explicit ItemEntries(const InstancedAccel& accel)
        : top(accel.top_level()),
          targets(accel.instance_targets().data()),
          views(accel.object_views().data()),
          start_leaf(start_leaf_of(accel.top_level())) {}

    /// enter_items_closest with this query's values.
    template <TriangleTest kTest>
    bool closest(NodeRef leaf, ObjectRayCache& object_rays, PreparedRay& world_ray, Hit& hit,
                 TraversalCounters* counters, HitTriangle* located,
                 const CloserHitObserver* observer) const {
        return enter_items_closest<kTest>(top, targets, views, start_leaf, leaf, object_rays,
                                          world_ray, hit, counters, located, observer);
    }

    /// Whether the ray hits anything among the items of `leaf`.
    template <TriangleTest kTest>
    bool occluded(NodeRef leaf, ObjectRayCache& object_rays) const {
        const std::uint32_t end = leaf.first_prim() + leaf.prim_count();
        for (std::uint32_t i = leaf.first_prim(); i < end; ++i) {
            const TopLevelItem& item = top.items[i];
            const InstanceTarget& target = targets[item.instance_id];
            PreparedRay& object_ray = object_rays.ray_for(target);
            if (occluded_object_bvh<kTest>(views[target.mesh], item.object_node, object_ray,
                                           nullptr, start_leaf))
                return true;
        }
        return false;
    }

    /// Prefetches what entering the first item of `leaf` reads first. A stacked item's
    /// object node is asked for as the item is stacked, as a flat BVH's stacked nodes are:
    /// its miss then overlaps the work on nearer items.
    void prefetch(NodeRef leaf) const {
        prefetch_item_target(top, targets, views, leaf, start_leaf);
    }
};

/// The slots of `node` whose hint words name a source (MergedTopLevel::kSourceWordFlag): in a
/// copied object node never none; in a top-level node, its hung object leaves.
inline unsigned source_word_slots(const WideNode& node) {
#ifdef REBRAID_SIMD_AVX2
    // The flag is each word's top bit, i.e. the sign bit of the 8 lanes.
    static_assert(MergedTopLevel::kSourceWordFlag == 0x80000000u);
    return unsigned(
        _mm256_movemask_ps(_mm256_loadu_ps(reinterpret_cast<const float*>(node.leaf_row_hints))));
#else
    unsigned slots = 0;
    for (int i = 0; i < kBvhWidth; ++i)
        slots |= unsigned((node.leaf_row_hints[i] & MergedTopLevel::kSourceWordFlag) != 0) << i;
    return slots;
#endif
}

/// The merged query's prefetcher: a stacked item's target (ItemEntries::prefetch), and, where
/// the structure's rows outgrow the caches (MergedTopLevel::rows_prefetch_from), the leaf rows
/// of the inner child of a copied node the traversal descends into: the child's hint, in the
/// rows of the source the node names.
struct MergedRowsPrefetch {
    const ItemEntries& entries;
    const MergedTopLevel& merged;
    std::uint32_t prefetch_from;

    void operator()(NodeRef leaf) const { entries.prefetch(leaf); }
    void rows_of_child(const WideNode& node, std::uint32_t node_id, int slot) const {
        if (node_id < prefetch_from) return;
        const std::uint32_t source_word =
            node.leaf_row_hints[std::countr_zero(source_word_slots(node))];
        LeafRowsPrefetch::prefetch_rows(merged.source_named_by(source_word).leaf_rows,
                                        node.leaf_row_hints[slot]);
    }
};

/// The closest hit of an instanced structure; with `located` given, also where the hit
/// triangle is kept and its corners (intersect_object_bvh), and `observer` (when not null)
/// told of each closer hit.
template <TriangleTest kTest>
Hit instanced_closest_hit(const InstancedAccel& accel, const Ray& ray, TraversalCounters* counters,
                          HitTriangle* located, const CloserHitObserver* observer) {
    Hit hit;  // one object every return names: no copy between the returns
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) {
        count_root_visit(counters);
        return hit;
    }
    PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
    ObjectRayCache object_rays(world_ray);
    const TopLevelBvh& top = accel.top_level();
    const InstanceTarget* targets = accel.instance_targets().data();
    const ObjectBvhView* views = accel.object_views().data();
    const StartLeaf start_leaf = start_leaf_of(top);
    const auto enter_items = [&](NodeRef leaf) {
        enter_items_closest<kTest>(top, targets, views, start_leaf, leaf, object_rays, world_ray,
                                   hit, counters, located, observer);
        return false;
    };
    // A stacked item's object node is asked for as the item is stacked, as a flat BVH's
    // stacked nodes are: its miss then overlaps the work on nearer items.
    const auto prefetch_item = [&top, targets, views, start_leaf](NodeRef leaf) {
        prefetch_item_target(top, targets, views, leaf, start_leaf);
    };
    traverse_bvh(top.nodes.data(), top.root, world_ray, counters, enter_items, prefetch_item);
    return hit;
}

template <TriangleTest kTest>
[[gnu::flatten]] bool instanced_occluded(const InstancedAccel& accel, const Ray& ray) {
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) return false;
    PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
    ObjectRayCache object_rays(world_ray);
    const ItemEntries entries(accel);
    // Any order: the first hit ends the query.
    return traverse_bvh<TraversalOrder::any>(
        entries.top.nodes.data(), entries.top.root, world_ray, nullptr,
        [&](NodeRef leaf) { return entries.occluded<kTest>(leaf, object_rays); });
}

/// The leaf slots of `node` whose hint words name a source: the object leaves of a merged top
/// level's node (leaf_slots and source_word_slots at once: both flags are their words' top
/// bits).
inline unsigned object_leaf_slots(const WideNode& node) {
#ifdef REBRAID_SIMD_AVX2
    static_assert(NodeRef::kLeafBit == MergedTopLevel::kSourceWordFlag);
    const auto words = [](const auto& array) {
        return _mm256_loadu_ps(reinterpret_cast<const float*>(array));
    };
    return unsigned(
        _mm256_movemask_ps(_mm256_and_ps(words(node.children), words(node.leaf_row_hints))));
#else
    return leaf_slots(node) & source_word_slots(node);
#endif
}

/// The leaf visitor of a merged top level (traverse_bvh's LeafVisits::by_node): object
/// leaves (every leaf child of a copied object node, and the leaves hung in a top-level node,
/// all of one source per node) go to `object_leaves(source, refs, slots)` together, top-level
/// items one by one to `items(leaf)`.
template <class ObjectLeaves, class Items>
struct MergedLeafVisitor {
    const MergedTopLevel& merged;
    ObjectLeaves object_leaves;
    Items items;

    unsigned sibling_leaf_slots(const WideNode& node) const { return object_leaf_slots(node); }
    bool operator()(const WideNode& node, unsigned slots) {
        return object_leaves(merged.source_of_leaves(node, slots), node.children, slots);
    }
    bool operator()(NodeRef leaf) { return items(leaf); }
};

/// The leaf visitor of a world tree (world_tree.h; traverse_bvh's LeafVisits::by_node): every
/// leaf child is an object leaf, each of the source its hint word names, and goes to
/// `leaves(source, refs, slot_bit)` on its own. Grouping a node's leaves by source (one call
/// per source) traced slower than a call per leaf.
template <class Leaves>
struct WorldTreeLeafVisitor {
    const MergedTopLevel& tree;
    Leaves leaves;

    unsigned sibling_leaf_slots(const WideNode& node) const { return leaf_slots(node); }
    bool operator()(const WideNode& node, unsigned slots) {
        do {
            const int slot = std::countr_zero(slots);
            slots &= slots - 1;
            if (leaves(tree.source_named_by(node.leaf_row_hints[slot]), node.children, 1u << slot))
                return true;
        } while (slots != 0);
        return false;
    }
    /// Never called: no leaf is left for one-by-one visits.
    bool operator()(NodeRef) { return false; }
};

/// The ray the triangles of merged `source` are tested with: the world ray, or for a placed
/// instance's subtree the ray mapped into its space (ObjectRayCache). The source's own copy of
/// the space decides, so a world-space source never reads its instance's record.
inline const TriangleGroupRay& source_triangle_ray(const MergedLeafSource& source,
                                                   PreparedRay& world_ray,
                                                   ObjectRayCache& object_rays) {
    if (source.space == InstanceTarget::kWorldSpace) return world_ray.triangle_ray;
    return object_rays.triangle_ray_for(*source.target);
}

/// Lanes over the leaves of `source`: its rows (SingleLeafRows) or its corners.
template <class Lanes>
Lanes source_lanes(const MergedLeafSource& source) {
    if constexpr (std::is_same_v<Lanes, LeafTriangleLanes>)
        return Lanes(source.triangles);
    else
        return Lanes(source.leaf_rows);
}

/// Calls `query.template operator()<Lanes>()` with the lanes type every merged source can
/// serve: the rows where the kernel reads rows and every merged BVH has them (one loop
/// without a choice per leaf, as intersect_object_bvh_leaf_order picks one per traversal).
template <class Query>
auto with_merged_lanes([[maybe_unused]] const MergedTopLevel& merged, Query&& query) {
#ifdef REBRAID_SIMD_AVX2
    if (merged.every_source_has_rows) return query.template operator()<SingleLeafRows>();
#endif
    return query.template operator()<LeafTriangleLanes>();
}

/// Tests the object leaves `slots` of `refs`, of merged `source`, with `ray` (the world ray, or
/// the ray mapped into the source's space) for a closest hit: a closer hit shortens `tfar` and
/// sets `hit` (its instance, and its primID, or with `hit_prim_ids` the leaf-order position
/// those turn into a primID when the query ends); `located` and `observer` as for
/// instanced_closest_hit.
template <TriangleTest kTest, class Lanes>
void closest_in_merged_leaves(Lanes& lanes, const MergedLeafSource& source, const NodeRef* refs,
                              unsigned slots, const TriangleGroupRay& ray, float tnear, float& tfar,
                              Hit& hit, const PrimId*& hit_prim_ids, TraversalCounters* counters,
                              HitTriangle* located, const CloserHitObserver* observer) {
    const auto test_lanes = [&] {
        TriangleGroupHit group_hit;
        if (lanes.template intersect<kTest>(
                ray, tnear, tfar, group_hit,
                located != nullptr ? &located->moller_terms : nullptr)) {
            tfar = group_hit.t;
            hit.t = group_hit.t;
            hit.u = group_hit.u;
            hit.v = group_hit.v;
            const std::uint32_t position = lanes.position(group_hit.index);
            hit.instance_id = source.instance;
            if (const std::optional<PrimId> id = row_prim_id(lanes, group_hit.index)) {
                hit.prim_id = *id;
                hit_prim_ids = nullptr;
            } else {
                hit.prim_id = position;
                hit_prim_ids = source.prim_ids;
                __builtin_prefetch(source.prim_ids + position);
            }
            if (located != nullptr) {
                located->leaf_position = position;
                located->corner_location = lanes.corner_location(group_hit.index);
                located->has_moller_terms = moller_terms_computed<kTest>();
                closer_hit_notifier(observer, source.instance)(*located);
            }
        }
    };
    test_each_leaf(lanes, refs, slots, counters, test_lanes, [] { return false; });
}

/// closest_in_merged_leaves over the source's own lanes.
template <TriangleTest kTest, class Lanes>
void closest_in_merged_leaves(const MergedLeafSource& source, const NodeRef* refs, unsigned slots,
                              const TriangleGroupRay& ray, float tnear, float& tfar, Hit& hit,
                              const PrimId*& hit_prim_ids, TraversalCounters* counters,
                              HitTriangle* located, const CloserHitObserver* observer) {
    Lanes lanes = source_lanes<Lanes>(source);
    closest_in_merged_leaves<kTest>(lanes, source, refs, slots, ray, tnear, tfar, hit, hit_prim_ids,
                                    counters, located, observer);
}

/// Whether the ray hits a triangle among the object leaves `slots` of `refs`, of merged
/// `source`, tested with `ray` (the world ray, or the ray mapped into the source's space).
template <TriangleTest kTest, class Lanes>
bool occluded_in_merged_leaves(Lanes& lanes, const NodeRef* refs, unsigned slots,
                               const TriangleGroupRay& ray, float tnear, float tfar) {
    bool is_occluded = false;
    const auto test_lanes = [&] {
        is_occluded = is_occluded || lanes.template occluded<kTest>(ray, tnear, tfar);
    };
    test_each_leaf(lanes, refs, slots, nullptr, test_lanes, [&] { return is_occluded; });
    return is_occluded;
}

/// occluded_in_merged_leaves over the leaves of merged `source`.
template <TriangleTest kTest, class Lanes>
bool occluded_in_merged_leaves(const MergedLeafSource& source, const NodeRef* refs, unsigned slots,
                               const TriangleGroupRay& ray, float tnear, float tfar) {
    Lanes lanes = source_lanes<Lanes>(source);
    return occluded_in_merged_leaves<kTest>(lanes, refs, slots, ray, tnear, tfar);
}

/// What a merged query's out-of-line part found (closest_in_placed_leaves,
/// closest_in_items): whether a closer hit, and then the hit, and the leaf-order ids its
/// primID is to be read from when the query ends (null: the hit names its primID).
struct OutOfLineHit {
    bool found = false;
    Hit hit;
    const PrimId* hit_prim_ids = nullptr;
};

// The parts of a merged query that most rays never reach, or reach seldom, are out of line
// (noinline), and take and give values only: the leaves of placed instances, with the world
// ray mapped into their space there, and the top-level items left to enter, each call with a
// world ray and ray cache of its own. The traversal's loop then keeps the world ray's values
// in registers and tests world-space leaves with them, where a mapped ray chosen per leaf run
// inside the loop, and the items' code beside it, had the compiler keep them in memory
// (docs/design.md, "The rare parts of a merged query out of line").

/// closest_in_merged_leaves for the leaves of a placed instance's source, with the world ray
/// (`org`, `dir`) mapped into the source's space here.
template <TriangleTest kTest, class Lanes>
[[gnu::noinline, gnu::flatten]] OutOfLineHit closest_in_placed_leaves(
    const MergedLeafSource& source, const NodeRef* refs, unsigned slots, Vec3f org, Vec3f dir,
    float tnear, float tfar, TraversalCounters* counters, HitTriangle* located,
    const CloserHitObserver* observer) {
    Vec3f object_org, object_dir;
    map_into_object_space(source.target->to_object, org, dir, object_org, object_dir);
    OutOfLineHit result;
    const float ray_end = tfar;
    closest_in_merged_leaves<kTest, Lanes>(
        source, refs, slots, TriangleGroupRay(object_org, object_dir), tnear, tfar, result.hit,
        result.hit_prim_ids, counters, located, observer);
    result.found = tfar < ray_end;
    return result;
}

/// occluded_in_merged_leaves for the leaves of a placed instance's source.
template <TriangleTest kTest, class Lanes>
[[gnu::noinline, gnu::flatten]] bool occluded_in_placed_leaves(const MergedLeafSource& source,
                                                               const NodeRef* refs, unsigned slots,
                                                               Vec3f org, Vec3f dir, float tnear,
                                                               float tfar) {
    Vec3f object_org, object_dir;
    map_into_object_space(source.target->to_object, org, dir, object_org, object_dir);
    return occluded_in_merged_leaves<kTest, Lanes>(
        source, refs, slots, TriangleGroupRay(object_org, object_dir), tnear, tfar);
}

/// Enters the items of top-level leaf `leaf` for the world ray `ray` (its slab terms
/// `slab_terms`) ending at `tfar`, as instanced_closest_hit does.
template <TriangleTest kTest>
[[gnu::noinline, gnu::flatten]] OutOfLineHit closest_in_items(
    const ItemEntries& entries, NodeRef leaf, const Ray& ray, const SlabTerms& slab_terms,
    float tfar, TraversalCounters* counters, HitTriangle* located,
    const CloserHitObserver* observer) {
    PreparedRay world_ray(ray.org, ray.dir, ray.tnear, tfar, slab_terms);
    ObjectRayCache object_rays(world_ray);
    OutOfLineHit result;
    result.found = entries.closest<kTest>(leaf, object_rays, world_ray, result.hit, counters,
                                          located, observer);
    return result;
}

/// Whether the world ray `ray` hits anything among the items of top-level leaf `leaf`.
template <TriangleTest kTest>
[[gnu::noinline, gnu::flatten]] bool occluded_in_items(const ItemEntries& entries, NodeRef leaf,
                                                       const Ray& ray,
                                                       const SlabTerms& slab_terms) {
    PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
    ObjectRayCache object_rays(world_ray);
    return entries.occluded<kTest>(leaf, object_rays);
}

/// The closest hit of an instanced structure whose world-space items are merged into its top
/// level (MergedTopLevel); `located` and `observer` as for instanced_closest_hit.
/// `kItemsOutOfLine`: the items left in the tree are entered out of line (closest_in_items;
/// MergedTopLevel::enters_items_out_of_line), else in the traversal's loop.
template <TriangleTest kTest, bool kItemsOutOfLine>
Hit merged_closest_hit(const InstancedAccel& accel, const Ray& ray, TraversalCounters* counters,
                       HitTriangle* located, const CloserHitObserver* observer) {
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) {
        count_root_visit(counters);
        return Hit{};
    }
    const MergedTopLevel& merged = accel.merged_top_level();
    return with_merged_lanes(merged, [&]<class Lanes>() {
        Hit hit;
        PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
        ObjectRayCache object_rays(world_ray);  // for the items and leaves tested in the loop
        const ItemEntries entries(accel);
        // A hit in a merged object leaf read from the corner storage keeps its leaf-order
        // position until the query ends, and these ids turn it into a primID then (as
        // intersect_object_bvh does: the lookup's miss overlaps the rest of the traversal);
        // null when the leaf rows gave the primID or an entered item gave the hit.
        const PrimId* hit_prim_ids = nullptr;
        const auto take = [&](const OutOfLineHit& found) {
            if (!found.found) return;
            world_ray.ray.tfar = found.hit.t;
            hit = found.hit;
            hit_prim_ids = found.hit_prim_ids;
        };
        const auto object_leaves = [&](const MergedLeafSource& source, const NodeRef* refs,
                                       unsigned slots) {
            TraversalRay& traversal = world_ray.ray;
            if constexpr (!kItemsOutOfLine) {
                closest_in_merged_leaves<kTest, Lanes>(
                    source, refs, slots, source_triangle_ray(source, world_ray, object_rays),
                    traversal.tnear, traversal.tfar, hit, hit_prim_ids, counters, located,
                    observer);
            } else if (source.space == InstanceTarget::kWorldSpace) {
                closest_in_merged_leaves<kTest, Lanes>(source, refs, slots, world_ray.triangle_ray,
                                                       traversal.tnear, traversal.tfar, hit,
                                                       hit_prim_ids, counters, located, observer);
            } else {
                take(closest_in_placed_leaves<kTest, Lanes>(source, refs, slots, ray.org, ray.dir,
                                                            ray.tnear, traversal.tfar, counters,
                                                            located, observer));
            }
            return false;
        };
        const auto items = [&](NodeRef leaf) {
            if constexpr (kItemsOutOfLine) {
                take(closest_in_items<kTest>(entries, leaf, ray, slab_terms, world_ray.ray.tfar,
                                             counters, located, observer));
            } else if (entries.closest<kTest>(leaf, object_rays, world_ray, hit, counters, located,
                                              observer)) {
                hit_prim_ids = nullptr;
            }
            return false;
        };
        MergedLeafVisitor<decltype(object_leaves), decltype(items)> visitor{merged, object_leaves,
                                                                            items};
        // Rows are asked for only where the lanes read them.
        constexpr bool kReadsRows = !std::is_same_v<Lanes, LeafTriangleLanes>;
        const MergedRowsPrefetch prefetch{
            entries, merged, kReadsRows ? merged.rows_prefetch_from : NodeRef::kEmptyBits};
        traverse_bvh<TraversalOrder::nearest_first, LeafVisits::by_node>(
            merged.nodes.data(), merged.root, world_ray, counters, visitor, prefetch);
        if (hit_prim_ids != nullptr) hit.prim_id = hit_prim_ids[hit.prim_id];
        return hit;
    });
}

template <TriangleTest kTest, bool kItemsOutOfLine>
[[gnu::flatten]] bool merged_occluded(const InstancedAccel& accel, const Ray& ray) {
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) return false;
    const MergedTopLevel& merged = accel.merged_top_level();
    return with_merged_lanes(merged, [&]<class Lanes>() {
        PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
        ObjectRayCache object_rays(world_ray);  // for the items and leaves tested in the loop
        const ItemEntries entries(accel);
        const auto object_leaves = [&](const MergedLeafSource& source, const NodeRef* refs,
                                       unsigned slots) {
            if constexpr (!kItemsOutOfLine) {
                return occluded_in_merged_leaves<kTest, Lanes>(
                    source, refs, slots, source_triangle_ray(source, world_ray, object_rays),
                    ray.tnear, ray.tfar);
            } else if (source.space == InstanceTarget::kWorldSpace) {
                return occluded_in_merged_leaves<kTest, Lanes>(
                    source, refs, slots, world_ray.triangle_ray, ray.tnear, ray.tfar);
            } else {
                return occluded_in_placed_leaves<kTest, Lanes>(source, refs, slots, ray.org,
                                                               ray.dir, ray.tnear, ray.tfar);
            }
        };
        const auto items = [&](NodeRef leaf) {
            if constexpr (kItemsOutOfLine)
                return occluded_in_items<kTest>(entries, leaf, ray, slab_terms);
            else
                return entries.occluded<kTest>(leaf, object_rays);
        };
        MergedLeafVisitor<decltype(object_leaves), decltype(items)> visitor{merged, object_leaves,
                                                                            items};
        // Any order: the first hit ends the query.
        return traverse_bvh<TraversalOrder::any, LeafVisits::by_node>(
            merged.nodes.data(), merged.root, world_ray, nullptr, visitor);
    });
}

/// The closest hit in a world tree (world_tree.h; MergedTopLevel::is_world_tree): one
/// traversal, nearest node first, and each leaf tested with the ray in its source's space,
/// mapped when the space differs from the last leaf's (ObjectRayCache); `located` and
/// `observer` as for instanced_closest_hit.
template <TriangleTest kTest>
Hit world_tree_closest_hit(const InstancedAccel& accel, const Ray& ray, TraversalCounters* counters,
                           HitTriangle* located, const CloserHitObserver* observer) {
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) {
        count_root_visit(counters);
        return Hit{};
    }
    const MergedTopLevel& tree = accel.merged_top_level();
    return with_merged_lanes(tree, [&]<class Lanes>() {
        Hit hit;
        PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
        ObjectRayCache object_rays(world_ray);
        const PrimId* hit_prim_ids = nullptr;
        // Every source's leaves are in the same arrays: the rows' address never waits on the
        // source's record, only the ray's mapping does.
        Lanes lanes = source_lanes<Lanes>(tree.sources.front());
        const auto leaves = [&](const MergedLeafSource& source, const NodeRef* refs,
                                unsigned slots) {
            TraversalRay& traversal = world_ray.ray;
            closest_in_merged_leaves<kTest>(
                lanes, source, refs, slots, source_triangle_ray(source, world_ray, object_rays),
                traversal.tnear, traversal.tfar, hit, hit_prim_ids, counters, located, observer);
            return false;
        };
        WorldTreeLeafVisitor<decltype(leaves)> visitor{tree, leaves};
        traverse_bvh<TraversalOrder::nearest_first, LeafVisits::by_node>(
            tree.nodes.data(), tree.root, world_ray, counters, visitor);
        if (hit_prim_ids != nullptr) hit.prim_id = hit_prim_ids[hit.prim_id];
        return hit;
    });
}

template <TriangleTest kTest>
[[gnu::flatten]] bool world_tree_occluded(const InstancedAccel& accel, const Ray& ray) {
    const SlabTerms slab_terms(ray);
    if (misses_root_box(accel.root_box(), ray, slab_terms)) return false;
    const MergedTopLevel& tree = accel.merged_top_level();
    return with_merged_lanes(tree, [&]<class Lanes>() {
        PreparedRay world_ray(ray.org, ray.dir, ray.tnear, ray.tfar, slab_terms);
        ObjectRayCache object_rays(world_ray);
        Lanes lanes = source_lanes<Lanes>(tree.sources.front());  // every source's arrays
        const auto leaves = [&](const MergedLeafSource& source, const NodeRef* refs,
                                unsigned slots) {
            return occluded_in_merged_leaves<kTest>(
                lanes, refs, slots, source_triangle_ray(source, world_ray, object_rays), ray.tnear,
                ray.tfar);
        };
        WorldTreeLeafVisitor<decltype(leaves)> visitor{tree, leaves};
        // Any order: the first hit ends the query.
        return traverse_bvh<TraversalOrder::any, LeafVisits::by_node>(tree.nodes.data(), tree.root,
                                                                      world_ray, nullptr, visitor);
    });
}

// The two entry points of a closest-hit query of an instanced structure (the general one,
// instanced_closest_hit, and the one-item one, sole_item_closest_hit): the plain hit, and the
// located hit with its observer.

template <auto closest_hit>
[[gnu::flatten]] Hit intersect_entry(const InstancedAccel& accel, const Ray& ray,
                                     TraversalCounters* counters) {
    return returned_hit(closest_hit(accel, ray, counters, nullptr, nullptr));
}

template <auto closest_hit>
[[gnu::flatten]] LocatedHit intersect_located_entry(const InstancedAccel& accel, const Ray& ray,
                                                    const CloserHitObserver* observer) {
    LocatedHit located;
    located.hit = returned_hit(closest_hit(accel, ray, nullptr, &located.triangle, observer));
    return located;
}

/// This level's entry points with the triangle test `kTest`.
template <TriangleTest kTest>
inline constexpr TraceKernels kLevelTraceKernels{
    &flat_intersect<kTest>,
    &flat_occluded<kTest>,
    &intersect_entry<&instanced_closest_hit<kTest>>,
    &instanced_occluded<kTest>,
    &intersect_located_entry<&instanced_closest_hit<kTest>>,
    &intersect_entry<&sole_item_closest_hit<kTest>>,
    &sole_item_occluded<kTest>,
    &intersect_located_entry<&sole_item_closest_hit<kTest>>,
    &intersect_entry<&merged_closest_hit<kTest, false>>,
    &merged_occluded<kTest, false>,
    &intersect_located_entry<&merged_closest_hit<kTest, false>>,
    &intersect_entry<&merged_closest_hit<kTest, true>>,
    &merged_occluded<kTest, true>,
    &intersect_located_entry<&merged_closest_hit<kTest, true>>,
    &intersect_entry<&world_tree_closest_hit<kTest>>,
    &world_tree_occluded<kTest>,
    &intersect_located_entry<&world_tree_closest_hit<kTest>>};

/// This level's entry points with the triangle test `test`.
inline const TraceKernels& level_trace_kernels(TriangleTest test) {
    return test == TriangleTest::moller ? kLevelTraceKernels<TriangleTest::moller>
                                        : kLevelTraceKernels<TriangleTest::watertight>;
}

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
