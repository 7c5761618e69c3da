#pragma once

#include <embree3/rtcore.h>

#include "embree_glue/dropin/embree_accel.h"

namespace rebraid {

/// The second drop-in mode, for applications that cannot change their rtcIntersect*/
/// rtcOccluded* call sites: a new RTCScene holding one user geometry whose callbacks answer
/// with `accel`. Tracing get() with rtcIntersect1/4/8/16 or rtcOccluded1/4/8/16 gives the
/// answers of EmbreeAccel::intersect1/occluded1 (the hit's geomID, primID and instID are those
/// of the original scene, not of the user geometry), at the cost of Embree's dispatch into
/// the callback (examples/dropin: dropin_example --bench). The intersection context's filter and flags are not
/// used.
///
/// `accel` must outlive this object. After accel.update(), call update() here too (the user
/// geometry's bounds may have changed).
class EmbreeUserGeometryScene {
public:
    /// Creates and commits the scene on the device of accel.rtc_scene(). Throws
    /// rebraid::Error when Embree refuses.
    explicit EmbreeUserGeometryScene(const EmbreeAccel& accel);
    ~EmbreeUserGeometryScene();

    EmbreeUserGeometryScene(const EmbreeUserGeometryScene&) = delete;
    EmbreeUserGeometryScene& operator=(const EmbreeUserGeometryScene&) = delete;

    /// The scene to trace instead of the application's one.
    RTCScene get() const { return scene_; }

    /// Commits again, so that Embree re-reads the bounds of the (updated) EmbreeAccel.
    void update();

private:
    const EmbreeAccel& accel_;
    RTCScene scene_ = nullptr;
    RTCGeometry geometry_ = nullptr;
};

}  // namespace rebraid
