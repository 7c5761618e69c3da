#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/root_box.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/core/transform.h"
#include "rebraid/core/triangle_test.h"
#include "rebraid/top_level/instance_target.h"
#include "rebraid/top_level/located_hit.h"
#include "rebraid/top_level/merged_top_level.h"
#include "rebraid/top_level/sole_item.h"
#include "rebraid/top_level/top_level_bvh.h"
#include "rebraid/top_level/trace_kernels.h"
#include "rebraid/top_level/two_level_builder.h"

namespace rebraid {

/// A two-level structure: object BVHs per mesh plus a top level whose leaves reference
/// (instance, object node) pairs. Serves both the plain two-level top and the re-braided one:
/// the same traversal runs on both (paper §5.5). A ray entering a leaf item is mapped into
/// the instance's object space once per item and continues at the item's object node; a top
/// level whose items are mostly in world space may be traced with their object subtrees
/// merged in instead (merged_top_level.h).
class InstancedAccel final : public Accel {
public:
    /// `build_info` carries the build timings and builder-specific figures (BRefs, budget)
    /// for stats(); the rest of the statistics are computed from the structure.
    /// `merge`: which object subtrees that the top level's items name are copied into the
    /// traced tree (MergedTopLevel); by default none.
    InstancedAccel(const Scene& scene, std::vector<ObjectBvh> object_bvhs, TopLevelBvh top,
                   const AccelStats& build_info,
                   const TopLevelMergeSettings& merge = {.world_space = false});
    // Movable, not copyable: object_views() point into the object BVHs' arrays, which a
    // move carries along and a copy would not.
    InstancedAccel(InstancedAccel&&) = default;
    InstancedAccel& operator=(InstancedAccel&&) = default;
    InstancedAccel(const InstancedAccel&) = delete;
    InstancedAccel& operator=(const InstancedAccel&) = delete;

    Hit intersect_counted(const Ray& ray, TraversalCounters* counters) const override;
    bool occluded(const Ray& ray) const override;
    AccelStats stats() const override;
    /// The closest hit, as intersect(), and its triangle (where it is kept, its corners);
    /// `observer`, when given, hears of every closer hit as it is found. Inline: the Embree
    /// glue calls it for every ray.
    LocatedHit intersect_located(const Ray& ray,
                                 const CloserHitObserver* observer = nullptr) const {
        return intersect_located_(*this, ray, observer);
    }

    const TopLevelBvh& top_level() const { return top_; }
    const std::vector<ObjectBvh>& object_bvhs() const { return object_bvhs_; }
    /// Hands the object BVHs back, e.g. to update them for the next frame of an animation
    /// without copying the static ones; the structure is then fit only for destruction.
    std::vector<ObjectBvh> release_object_bvhs() && { return std::move(object_bvhs_); }
    /// Hands the top level back, e.g. for an incremental top to rebuild the next frame's in
    /// the same arrays; the structure is then fit only for destruction or
    /// release_object_bvhs().
    TopLevelBvh release_top_level() && { return std::move(top_); }
    /// Mesh of each instance (index = InstanceId).
    const std::vector<std::uint32_t>& instance_meshes() const { return instance_mesh_; }
    /// What entering each instance reads (index = InstanceId), made at construction.
    const std::vector<InstanceTarget>& instance_targets() const { return instance_targets_; }
    /// The arrays traversal reads of each mesh's object BVH (index = MeshId).
    const std::vector<ObjectBvhView>& object_views() const { return object_views_; }
    /// The top level's one item, where it holds only one (the sole-item queries read it); not
    /// meaningful otherwise.
    const SoleItem& sole_item() const { return sole_item_; }
    /// The top level with its world-space items' object nodes copied in, which queries
    /// traverse instead of the top level when it is not empty (merged_top_level.h).
    const MergedTopLevel& merged_top_level() const { return merged_; }
    /// The box around the root children of the tree queries traverse (the merged top level,
    /// the top level, or a sole item's object BVH where its instance is placed by the
    /// identity), which they test first (root_box_cull.h); all of space where they do not
    /// (set_culls_root_box).
    const RootBox& root_box() const { return root_box_; }
    /// Whether queries test the root box first: on at construction. A caller that screens
    /// every ray against the scene's box itself before it queries (the Embree glue) turns it
    /// off: the box is then all of space, and a query checks that the origin lies in it
    /// instead of testing the ray's slabs against the box a second time. The same hits
    /// either way. Not while tracing.
    void set_culls_root_box(bool culls);
    bool culls_root_box() const { return culls_root_box_; }

    /// Replaces the world-to-object map of every instance not placed by the identity with
    /// `world_to_object[i]` (index = InstanceId; each an inverse of the instance's
    /// object_to_world, computed another way): the maps rays are traced with from now on.
    /// The drop-in passes Embree's own inverses, so that its rays enter objects with Embree's
    /// bits (trace_kernel_bodies.h, map_into_object_space). Throws rebraid::Error when the
    /// count differs from the instances'. Not while tracing.
    void set_world_to_object(std::span<const AffineTransform> world_to_object);

    /// The kernel level rays are traced with: default_simd_level() at construction.
    SimdLevel simd_level() const { return simd_level_; }
    /// Traces with `level`'s kernels from now on (same hits at every level; to compare them).
    /// Throws rebraid::Error when this build or CPU cannot run it. Not while tracing.
    void set_simd_level(SimdLevel level);
    /// The triangle test rays are traced with: TriangleTest::moller (Embree's default) at
    /// construction.
    TriangleTest triangle_test() const { return triangle_test_; }
    /// Traces with `test` from now on (TriangleTest::watertight for Embree's robust mode). Not
    /// while tracing.
    void set_triangle_test(TriangleTest test);

private:
    std::vector<ObjectBvh> object_bvhs_;
    TopLevelBvh top_;
    std::vector<std::uint32_t> instance_mesh_;
    std::vector<AffineTransform> object_to_world_;
    std::vector<InstanceTarget> instance_targets_;
    std::vector<ObjectBvhView> object_views_;
    MergedTopLevel merged_;
    AccelStats build_info_;
    SimdLevel simd_level_;
    TriangleTest triangle_test_ = TriangleTest::moller;
    // The entry points of the kernel level the queries take: a top level of one item has
    // queries of its own (TraceKernels::sole_item_intersect), chosen here once rather than
    // tested in every query.
    decltype(TraceKernels::instanced_intersect) intersect_ = nullptr;
    decltype(TraceKernels::instanced_occluded) occluded_ = nullptr;
    decltype(TraceKernels::instanced_intersect_located) intersect_located_ = nullptr;
    SoleItem sole_item_;
    RootBox root_box_;
    bool culls_root_box_ = true;

    void use_kernels(SimdLevel level, TriangleTest test);
    /// Whether the top level holds one item (its root a leaf of one item).
    bool has_sole_item() const;
    /// Copies the top level's one item, its instance's target and its mesh's arrays into
    /// sole_item_ (when the top level holds one item).
    void refresh_sole_item();
    /// Sets root_box_ for the tree queries traverse, or to all of space where they do not
    /// cull (culls_root_box_).
    void refresh_root_box();
};

/// Object BVHs from `object_builder`, then the plain two-level top (two_level_builder.h).
InstancedAccel build_two_level_accel(
    const Scene& scene, const ObjectBvhBuilder& object_builder = own_object_bvh_builder(),
    const BuildSettings& top_settings = default_top_level_settings());

}  // namespace rebraid
