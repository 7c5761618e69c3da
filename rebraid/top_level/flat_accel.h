#pragma once

#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/root_box.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/core/triangle_test.h"
#include "rebraid/top_level/flat_hit_ids.h"

namespace rebraid {

struct TraceKernels;

/// One BVH over every instance's triangles in world space: no instancing, the quality
/// reference (and the memory cost two-level structures avoid).
class FlatAccel final : public Accel {
public:
    explicit FlatAccel(const Scene& scene,
                       const BuildSettings& settings = static_object_build_settings());

    Hit intersect_counted(const Ray& ray, TraversalCounters* counters) const override;
    bool occluded(const Ray& ray) const override;
    AccelStats stats() const override;

    const ObjectBvh& bvh() const { return bvh_; }
    /// The box around the BVH's root children, which queries test first (root_box_cull.h).
    const RootBox& root_box() const { return root_box_; }
    /// Instance and primID of each world triangle (index = the flat BVH's primID).
    const std::vector<InstanceId>& triangle_instances() const { return triangle_instance_; }
    const std::vector<PrimId>& triangle_prims() const { return triangle_prim_; }
    /// How the leaf rows name a hit's instance and primID, where they can (flat_hit_ids.h).
    const FlatHitIds& hit_ids() const { return hit_ids_; }

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
    /// Chooses hit_ids_ and writes the leaf rows' id row to match.
    void write_hit_ids(const Scene& scene);

    ObjectBvh bvh_;
    std::vector<InstanceId> triangle_instance_;
    std::vector<PrimId> triangle_prim_;
    FlatHitIds hit_ids_;
    AccelStats build_info_;
    SimdLevel simd_level_;
    TriangleTest triangle_test_ = TriangleTest::moller;
    const TraceKernels* kernels_;
    RootBox root_box_;
};

}  // namespace rebraid
