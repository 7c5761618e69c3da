#pragma once

#include <embree3/rtcore.h>

#include <string>
#include <vector>

#include "embree_glue/reference/embree_device.h"
#include "embree_glue/reference/embree_scene_handle.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"

namespace rebraid::glue {

/// Embree's BVH build quality, as a plain enum so settings need no RTC types.
enum class EmbreeBuildQuality {
    /// Fast build, slower traversal. Embree then builds a two-level structure (one BVH per
    /// geometry plus a top level), even for the flat reference.
    low,
    /// Embree's default: a good compromise between build and traversal speed.
    medium,
    /// Slowest build, fastest traversal: adds spatial splits for triangles.
    high,
};

/// Parameters shared by both Embree reference structures.
struct EmbreeReferenceSettings {
    /// Build quality of every Embree scene (and geometry) the structure creates.
    EmbreeBuildQuality build_quality = EmbreeBuildQuality::medium;
    /// RTC_SCENE_FLAG_ROBUST: robust traversal, no accuracy-reducing shortcuts. On by default
    /// because these structures are the oracle other structures are checked against: a ray
    /// through the edge shared by two triangles must hit one of them, not slip through the
    /// crack between them. Off traces a little faster.
    bool is_robust = true;
    /// Embree device config string ("threads=2", "verbose=1", ...); empty = Embree's defaults.
    std::string device_config;
};

/// Largest |coordinate| Embree's ray validity check accepts (its FLT_LARGE is 1.844e18),
/// rounded down.
inline constexpr float kEmbreeLargestRayCoordinate = 1.8e18f;

/// Bounds on a ray's coordinates beyond which Embree would assert (and abort the process).
/// For instances they apply to the ray mapped into object space, so a structure derives its
/// world-space limits from its transforms.
struct EmbreeRayLimits {
    float max_origin_coordinate = kEmbreeLargestRayCoordinate;     ///< |org.x|, |org.y|, |org.z|
    float max_direction_coordinate = kEmbreeLargestRayCoordinate;  ///< |dir.x|, |dir.y|, |dir.z|
};

/// Whether `ray` is handed to Embree at all, as both structures below decide: false for an empty
/// or NaN segment (no t satisfies tnear <= t <= tfar: a miss by contract, Embree is not
/// called); throws rebraid::Error, naming `accel_name`, for a ray Embree cannot trace under
/// `limits` (negative tnear, a coordinate not finite or beyond them).
bool is_traced_by_embree(const Ray& ray, const EmbreeRayLimits& limits, const char* accel_name);

/// `embree-flat`: one Embree scene holding every instance's triangles transformed to world
/// space. Each instance becomes its own triangle geometry whose geomID is the instance id, so
/// hits name their instance without a lookup table; at medium/high quality Embree still builds
/// a single BVH over the triangles of all geometries together.
///
/// Rays follow Embree's contract, which Debian's libembree3 enforces with assertions that
/// abort the process, so they are checked first: an empty or NaN segment (not tnear <= tfar)
/// is a miss without calling Embree; a negative tnear or a non-finite origin or direction (or
/// one beyond ray_limits()) throws rebraid::Error, since Embree cannot answer it. Hits at exactly
/// tnear or tfar may or may not be reported (Embree gives no guarantee there).
class EmbreeFlatAccel final : public Accel {
public:
    /// Builds the structure; throws rebraid::Error for an invalid scene or any Embree error.
    explicit EmbreeFlatAccel(const Scene& scene, const EmbreeReferenceSettings& settings = {});

    /// rtcIntersect1. `counters` are left untouched: Embree does not report its work.
    Hit intersect_counted(const Ray& ray, TraversalCounters* counters) const override;
    /// rtcOccluded1.
    bool occluded(const Ray& ray) const override;
    /// Input counts, build time (geometry creation + commit) and Embree's allocated bytes.
    AccelStats stats() const override;

    /// The committed scene, for callers that query Embree directly.
    RTCScene rtc_scene() const { return scene_.get(); }
    /// Rays beyond these are rejected: Embree's own limits.
    EmbreeRayLimits ray_limits() const { return {}; }

private:
    EmbreeDevice device_;  // declared first: destroyed after the scene that uses it
    EmbreeSceneHandle scene_;
    AccelStats stats_;
};

/// `embree-instanced`: one Embree scene per mesh (a single triangle geometry in object space)
/// and one instance geometry per instance in a top scene, geomID = instance id. Hits report
/// instID[0] as the instance id. Ray handling as EmbreeFlatAccel, with ray_limits() derived
/// from the instance transforms. Throws rebraid::Error at construction for a transform whose
/// float inverse is not finite (Embree would produce NaN object-space rays from it).
class EmbreeInstancedAccel final : public Accel {
public:
    /// Builds the structure; throws rebraid::Error for an invalid scene or any Embree error.
    explicit EmbreeInstancedAccel(const Scene& scene, const EmbreeReferenceSettings& settings = {});

    /// rtcIntersect1. `counters` are left untouched: Embree does not report its work.
    Hit intersect_counted(const Ray& ray, TraversalCounters* counters) const override;
    /// rtcOccluded1.
    bool occluded(const Ray& ray) const override;
    /// Input counts, build time (all scenes created + committed) and Embree's allocated bytes.
    AccelStats stats() const override;

    /// The committed top-level scene, for callers that query Embree directly.
    RTCScene rtc_scene() const { return top_scene_.get(); }
    /// Rays beyond these are rejected: Embree's limits, tightened so that the ray mapped into
    /// any instance's object space still satisfies them.
    EmbreeRayLimits ray_limits() const { return ray_limits_; }

private:
    EmbreeDevice device_;  // declared first: destroyed after the scenes that use it
    std::vector<EmbreeSceneHandle> mesh_scenes_;  ///< index = MeshId
    EmbreeSceneHandle top_scene_;
    AccelStats stats_;
    EmbreeRayLimits ray_limits_;
};

}  // namespace rebraid::glue
