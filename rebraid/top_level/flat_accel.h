#pragma once

#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// One BVH over every instance's triangles in world space: no instancing, the quality
/// reference (and the memory cost two-level structures avoid).
class FlatAccel final : public Accel {
public:
    explicit FlatAccel(const Scene& scene, const BuildSettings& settings = {});

    Hit intersect_counted(const Ray& ray, TraversalCounters* counters) const override;
    bool occluded(const Ray& ray) const override;
    AccelStats stats() const override;

    const ObjectBvh& bvh() const { return bvh_; }
    /// Instance and primID of each world triangle (index = the flat BVH's primID).
    const std::vector<InstanceId>& triangle_instances() const { return triangle_instance_; }
    const std::vector<PrimId>& triangle_prims() const { return triangle_prim_; }

private:
    ObjectBvh bvh_;
    std::vector<InstanceId> triangle_instance_;
    std::vector<PrimId> triangle_prim_;
    AccelStats build_info_;
};

}  // namespace rebraid
