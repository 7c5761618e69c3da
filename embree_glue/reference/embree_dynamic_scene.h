#pragma once

#include <embree3/rtcore.h>

#include <string_view>
#include <vector>

#include "embree_glue/reference/embree_device.h"
#include "embree_glue/reference/embree_reference.h"
#include "embree_glue/reference/embree_scene_handle.h"
#include "rebraid/core/accel.h"
#include "rebraid/dynamic/dynamic_scene.h"

namespace rebraid::glue {

/// How Embree follows a DynamicScene from frame to frame: what a user of Embree would do.
enum class EmbreeDynamicMode {
    /// "embree-flat": every instance's triangles in world space, one geometry per instance
    /// (geomID = instance id); changed geometries rewritten, then one scene commit, which
    /// rebuilds the single BVH over all triangles.
    flat,
    /// "embree-flat-refit": as flat, but the scene is RTC_SCENE_FLAG_DYNAMIC and the changed
    /// geometries have RTC_BUILD_QUALITY_REFIT, so Embree keeps a BVH per geometry, refits
    /// the changed ones and rebuilds only its own top level over them.
    flat_refit,
    /// "embree-instanced": one scene per mesh and an instance per instance; dynamic meshes
    /// (RTC_BUILD_QUALITY_REFIT in an RTC_SCENE_FLAG_DYNAMIC scene) updated and committed,
    /// moved instances re-transformed, then the top scene committed.
    instanced,
};

/// The method name the animate command prints ("embree-flat", ...).
std::string_view embree_dynamic_mode_name(EmbreeDynamicMode mode);

/// What one frame's update cost.
struct EmbreeFrameTimes {
    double update_ms = 0.0;  ///< changed geometry buffers written and geometries committed
    double top_ms = 0.0;     ///< the scene commit (flat) or the top scene commit (instanced)
};

/// An Embree structure over a DynamicScene that follows its animation (the alternatives the
/// dynamic-in-static benchmark measures). Hits name instances and primitives as every other
/// structure does. Not thread-safe while update() runs; intersect/occluded are.
class EmbreeDynamicAccel final : public Accel {
public:
    /// Builds the structure at the scene's current pose. The dynamic scene must outlive this.
    /// Throws rebraid::Error on any Embree error.
    EmbreeDynamicAccel(const DynamicScene& scene, EmbreeDynamicMode mode,
                       const EmbreeReferenceSettings& settings = {});

    /// Follows the scene to its current pose (call after DynamicScene::pose()).
    EmbreeFrameTimes update();

    Hit intersect_counted(const Ray& ray, TraversalCounters* counters) const override;
    bool occluded(const Ray& ray) const override;
    /// Input counts, first build time and Embree's allocated bytes; Embree's BVHs have no SAH.
    AccelStats stats() const override;

    /// The committed scene rays are traced in (flat: the scene; instanced: the top), for
    /// callers that query Embree directly (EmbreeRayBatch).
    RTCScene rtc_scene() const { return top_scene_.get(); }
    /// True when hits name their instance by instID[0] (instanced), false by geomID (flat).
    bool names_instances_by_inst_id() const { return mode_ == EmbreeDynamicMode::instanced; }
    /// Whether `ray` is handed to Embree: false for an empty segment (a miss); throws
    /// rebraid::Error for a ray Debian's Embree would assert on (negative tnear, non-finite
    /// origin or direction).
    static bool is_traced_by_embree(const Ray& ray);

private:
    void build_flat();
    void build_instanced();

    const DynamicScene& scene_;
    EmbreeDynamicMode mode_;
    EmbreeReferenceSettings settings_;
    EmbreeDevice device_;  // declared before the scenes: destroyed after them
    std::vector<EmbreeSceneHandle> mesh_scenes_;  ///< instanced: index = MeshId
    EmbreeSceneHandle top_scene_;                 ///< flat: the scene; instanced: the top
    std::vector<RTCGeometry> geometries_;  ///< flat: per instance; instanced: per mesh (borrowed)
    std::vector<RTCGeometry> instance_geometries_;  ///< instanced: per instance (borrowed)
    AccelStats stats_;
};

}  // namespace rebraid::glue
