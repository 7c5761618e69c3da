#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <optional>

#include "rebraid/bvh/hit_triangle.h"
#include "rebraid/bvh/leaf_row_hints.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/single_leaf_rows.h"
#include "rebraid/bvh/traversal.h"
#include "rebraid/bvh/triangle_group.h"
#include "rebraid/core/simd_config.h"
#include "rebraid/core/triangle_test.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// What a leaf a query starts at may be: a whole leaf of the object BVH, or, in a re-braided
/// top whose BRefs opened leaves into single triangles (TopLevelBvh::has_partial_leaves),
/// part of one. The pre-arranged rows address whole leaves only; part of a leaf is read from
/// the corner storage.
enum class StartLeaf { whole, may_be_part };

/// Whether a query that starts at `start` reads the pre-arranged rows of `bvh` (the SIMD
/// kernels, when the rows were made) rather than the corner storage.
inline bool rows_serve([[maybe_unused]] ObjectBvhView bvh, [[maybe_unused]] NodeRef start,
                       [[maybe_unused]] StartLeaf start_leaf) {
#ifdef REBRAID_SIMD_AVX2
    return bvh.leaf_rows != nullptr && (start.is_inner() || start_leaf == StartLeaf::whole);
#else
    return false;
#endif
}

/// A closer-hit callback that does nothing (intersect_object_bvh_leaf_order's default).
struct NoHitDataPrefetch {
    void operator()(std::uint32_t, CornerLocation, std::optional<PrimId>) const {}
};

/// The triangles of a leaf (a leaf-order range of one BVH) in the lanes of group tests, 8 at a
/// time, from the corner storage (test_each_leaf).
class LeafTriangleLanes {
public:
    explicit LeafTriangleLanes(const TriangleVerts* triangles) : triangles_(triangles) {}

    /// Calls `test()` for the leaf's triangles, 8 at a time (a leaf of more than 8 takes one
    /// test per 8).
    template <class Test>
    void test_leaf(NodeRef leaf, Test&& test) {
        const TriangleVerts* first = triangles_ + leaf.first_prim();
        const std::uint32_t count = leaf.prim_count();
        for (std::uint32_t done = 0; done < count; done += kTriangleGroupSize) {
            count_ = std::min(count - done, kTriangleGroupSize);
            for (std::uint32_t i = 0; i < count_; ++i) lanes_[i] = first + done + i;
            test();
        }
    }
    /// The closest of the lanes' triangles the ray hits within [tnear, tfar], if any, by
    /// the test `kTest` (and its terms in `terms`, when given: intersect_triangle_lanes).
    template <TriangleTest kTest>
    bool intersect(const TriangleGroupRay& ray, float tnear, float tfar, TriangleGroupHit& hit,
                   MollerTerms* terms = nullptr) const {
        return intersect_triangle_lanes<kTest>(lanes_, count_, ray, tnear, tfar, hit, terms);
    }
    /// Whether the ray hits any of the lanes' triangles within [tnear, tfar].
    template <TriangleTest kTest>
    bool occluded(const TriangleGroupRay& ray, float tnear, float tfar) const {
        return occluded_triangle_lanes<kTest>(lanes_, count_, ray, tnear, tfar);
    }
    /// Leaf-order position of the triangle in `lane`.
    std::uint32_t position(std::uint32_t lane) const {
        return std::uint32_t(lanes_[lane] - triangles_);
    }
    /// Where the triangle in `lane` keeps its corners.
    CornerLocation corner_location(std::uint32_t lane) const { return {lanes_[lane]}; }

private:
    const TriangleVerts* triangles_;
    const TriangleVerts* lanes_[kTriangleGroupSize];  // left uninitialised: filled as used
    std::uint32_t count_ = 0;
};

/// Tests the leaves bit i of `slots` selects in `refs`, each on its own in slot order, through
/// `lanes` (LeafTriangleLanes or SingleLeafRows), counting their triangles in `counters` when
/// given; `test()` tests what the lanes hold. Stops once `is_done()` (any-hit
/// queries: a hit was found). The object BVH queries and the merged top level test leaves so:
/// gathering sibling leaves into shared tests traced the flat BVH 2-8 % slower (docs/design.md,
/// "Leaves"), the gathering's bookkeeping on the path every test waits on.
template <class Lanes, class Test, class IsDone>
void test_each_leaf(Lanes& lanes, const NodeRef* refs, unsigned slots, TraversalCounters* counters,
                    Test&& test, IsDone&& is_done) {
    do {
        const NodeRef leaf = refs[std::countr_zero(slots)];
        slots &= slots - 1;
        if (counters) counters->triangles_tested += leaf.prim_count();
        lanes.test_leaf(leaf, test);
    } while (slots && !is_done());
}

/// Whether this kernel's closest-hit queries with the test `kTest` give a hit's Möller terms
/// (MollerTerms): the SIMD kernels' Möller test does.
template <TriangleTest kTest>
constexpr bool moller_terms_computed() {
#ifdef REBRAID_SIMD_AVX2
    return kTest == TriangleTest::moller;
#else
    return false;
#endif
}

/// The primID of the triangle in `lane` where the lanes' storage holds it (leaf rows).
template <class Lanes>
std::optional<PrimId> row_prim_id([[maybe_unused]] const Lanes& lanes,
                                  [[maybe_unused]] std::uint32_t lane) {
    if constexpr (requires { Lanes::kHoldsPrimIds; })
        return lanes.prim_id(lane);
    else
        return std::nullopt;
}

namespace object_traversal_detail {

/// intersect_object_bvh_leaf_order with `lanes` holding the leaves' triangles.
template <TriangleTest kTest, class Lanes, class HitDataPrefetch>
bool intersect_with_lanes(Lanes& lanes, ObjectBvhView bvh, NodeRef start, PreparedRay& prepared,
                          Hit& hit, TraversalCounters* counters,
                          HitDataPrefetch&& prefetch_hit_data, MollerTerms* terms) {
    const WideNode* nodes = bvh.nodes;
    TraversalRay& ray = prepared.ray;
    const TriangleGroupRay& group_ray = prepared.triangle_ray;
    bool found = false;
    const auto test_lanes = [&] {
        TriangleGroupHit group_hit;
        if (lanes.template intersect<kTest>(group_ray, ray.tnear, ray.tfar, group_hit, terms)) {
            ray.tfar = group_hit.t;
            hit.t = group_hit.t;
            hit.u = group_hit.u;
            hit.v = group_hit.v;
            hit.prim_id = lanes.position(group_hit.index);
            prefetch_hit_data(hit.prim_id, lanes.corner_location(group_hit.index),
                              row_prim_id(lanes, group_hit.index));
            found = true;
        }
    };
    // Sibling leaves before the node's inner children (LeafVisits::with_siblings).
    const auto visit_leaves = [&](const NodeRef* refs, unsigned slots) {
        test_each_leaf(lanes, refs, slots, counters, test_lanes, [] { return false; });
        return false;
    };
    // Two traversals, with and without asking for rows ahead, rather than one testing a flag
    // at every descent: the flag, live through the loop, cost the flat BVH 5 % on the default
    // scene (bench/tools/kernel_ab.py).
    constexpr TraversalOrder kOrder = TraversalOrder::nearest_first;
    constexpr LeafVisits kVisits = LeafVisits::with_siblings;
    if constexpr (requires { lanes.rows(); }) {
        if (bvh.prefetches_rows) {
            traverse_bvh<kOrder, kVisits>(nodes, start, prepared, counters, visit_leaves,
                                          LeafRowsPrefetch{lanes.rows()});
            return found;
        }
    }
    traverse_bvh<kOrder, kVisits>(nodes, start, prepared, counters, visit_leaves);
    return found;
}

/// occluded_object_bvh with `lanes` holding the leaves' triangles.
template <TriangleTest kTest, class Lanes>
bool occluded_with_lanes(Lanes& lanes, const WideNode* nodes, NodeRef start, PreparedRay& prepared,
                         TraversalCounters* counters) {
    const TraversalRay& ray = prepared.ray;
    const TriangleGroupRay& group_ray = prepared.triangle_ray;
    bool is_occluded = false;
    const auto test_lanes = [&] {
        is_occluded = is_occluded || lanes.template occluded<kTest>(group_ray, ray.tnear, ray.tfar);
    };
    const auto visit_leaves = [&](const NodeRef* refs, unsigned slots) {
        test_each_leaf(lanes, refs, slots, counters, test_lanes, [&] { return is_occluded; });
        return is_occluded;
    };
    // Any order: the first hit ends the query, and sorting the children costs more than the
    // nearer hits it would find first (measured on the shared scenes).
    return traverse_bvh<TraversalOrder::any, LeafVisits::with_siblings>(nodes, start, prepared,
                                                                        counters, visit_leaves);
}

}  // namespace object_traversal_detail

/// Closest hit among the triangles below `start` (any node of `bvh`) by the triangle test
/// `kTest`, for a ray already in the BVH's space. On a closer hit sets ray.tfar and hit.t/u/v, and
/// hit.prim_id to the hit's position in leaf order (index into bvh.prim_ids and bvh.triangles), and
/// returns true; leaves hit.instance_id to the caller. `prefetch_hit_data(position, corners,
/// row_id)` is called with the leaf-order position of every closer hit as it is found,
/// `corners` where the leaf data the test has just read keeps that triangle's corners, and
/// `row_id` its primID where that data holds it (leaf rows; else nullopt): the caller prefetches
/// what it will look up for the final hit (ids in leaf order), so that the lookup's cache miss
/// overlaps the rest of the traversal, or notes where the corners are. (Asking for every visited
/// leaf's ids instead cost more than the misses it hid.) `start_leaf` says what a leaf `start` may
/// be (StartLeaf). With `terms` given, a SIMD kernel's Möller test writes each closer hit's terms
/// there before `prefetch_hit_data` is called (moller_terms_computed).
template <TriangleTest kTest, class HitDataPrefetch = NoHitDataPrefetch>
bool intersect_object_bvh_leaf_order(ObjectBvhView bvh, NodeRef start, PreparedRay& prepared,
                                     Hit& hit, TraversalCounters* counters,
                                     HitDataPrefetch&& prefetch_hit_data = {},
                                     [[maybe_unused]] StartLeaf start_leaf = StartLeaf::whole,
                                     MollerTerms* terms = nullptr) {
    using namespace object_traversal_detail;
#ifdef REBRAID_SIMD_AVX2
    if (rows_serve(bvh, start, start_leaf)) {
        SingleLeafRows lanes(bvh.leaf_rows);
        return intersect_with_lanes<kTest>(lanes, bvh, start, prepared, hit, counters,
                                           prefetch_hit_data, terms);
    }
#endif
    LeafTriangleLanes lanes(bvh.triangles);
    return intersect_with_lanes<kTest>(lanes, bvh, start, prepared, hit, counters,
                                       prefetch_hit_data, terms);
}

/// Closest hit among the triangles below `start` (any node of `bvh`) by the triangle test
/// `kTest`, for a ray already in the BVH's space. On a closer hit sets ray.tfar and
/// hit.t/u/v/prim_id (mesh primID) and returns true; leaves hit.instance_id to the caller. With
/// `located` given, also sets located->leaf_position to the hit's leaf-order position and
/// located->corner_location to where the leaf data the test read keeps its corners, and its
/// Möller terms where this kernel computes them (moller_terms_computed), as each closer hit is
/// found, and then calls `on_closer_hit(*located)`. `start_leaf`: see StartLeaf.
template <TriangleTest kTest, class OnCloserHit = void (*)(const HitTriangle&)>
bool intersect_object_bvh(
    ObjectBvhView bvh, NodeRef start, PreparedRay& ray, Hit& hit, TraversalCounters* counters,
    HitTriangle* located = nullptr, OnCloserHit&& on_closer_hit = [](const HitTriangle&) {},
    StartLeaf start_leaf = StartLeaf::whole) {
    Hit leaf_order_hit = hit;
    const PrimId* prim_ids = bvh.prim_ids;
    // The closest hit's primID where its leaf's rows gave it (no lookup after the query).
    std::optional<PrimId> row_id;
    const auto prefetch_hit_data = [&](std::uint32_t position, CornerLocation corners,
                                       std::optional<PrimId> id_from_rows) {
        row_id = id_from_rows;
        if (!row_id) __builtin_prefetch(prim_ids + position);
        if (located != nullptr) {
            located->leaf_position = position;
            located->corner_location = corners;
            located->has_moller_terms = moller_terms_computed<kTest>();
            on_closer_hit(*located);
        }
    };
    if (!intersect_object_bvh_leaf_order<kTest>(
            bvh, start, ray, leaf_order_hit, counters, prefetch_hit_data, start_leaf,
            located != nullptr ? &located->moller_terms : nullptr))
        return false;
    hit = leaf_order_hit;
    hit.prim_id = row_id ? *row_id : prim_ids[leaf_order_hit.prim_id];
    return true;
}

/// True when any triangle below `start` is hit within [ray.tnear, ray.tfar] by the triangle
/// test `kTest`; `start_leaf` as for intersect_object_bvh_leaf_order.
template <TriangleTest kTest>
bool occluded_object_bvh(ObjectBvhView bvh, NodeRef start, PreparedRay& prepared,
                         TraversalCounters* counters,
                         [[maybe_unused]] StartLeaf start_leaf = StartLeaf::whole) {
    using namespace object_traversal_detail;
#ifdef REBRAID_SIMD_AVX2
    if (rows_serve(bvh, start, start_leaf)) {
        SingleLeafRows lanes(bvh.leaf_rows);
        return occluded_with_lanes<kTest>(lanes, bvh.nodes, start, prepared, counters);
    }
#endif
    LeafTriangleLanes lanes(bvh.triangles);
    return occluded_with_lanes<kTest>(lanes, bvh.nodes, start, prepared, counters);
}

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
