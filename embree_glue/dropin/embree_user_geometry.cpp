#include "embree_glue/dropin/embree_user_geometry.h"

#include "rebraid/core/error.h"

namespace rebraid {
namespace {

const EmbreeAccel& accel_of(void* user) {
    return *static_cast<const EmbreeAccel*>(user);
}

void bounds_callback(const RTCBoundsFunctionArguments* args) {
    const BBox3f& bounds = accel_of(args->geometryUserPtr).bounds();
    *args->bounds_o = {bounds.min.x, bounds.min.y, bounds.min.z, 0.0f,
                       bounds.max.x, bounds.max.y, bounds.max.z, 0.0f};
}

// The callbacks screen each ray (intersect1, occluded1) although Embree knows the primitive's
// box: its BVH over the one primitive is a leaf, so it calls them for every ray it traces.

void intersect_callback(const RTCIntersectFunctionNArguments* args) {
    const EmbreeAccel& accel = accel_of(args->geometryUserPtr);
    if (args->N == 1) {
        // A packet of one is laid out exactly as an RTCRayHit.
        if (args->valid[0] != 0) accel.intersect1(*reinterpret_cast<RTCRayHit*>(args->rayhit));
        return;
    }
    for (unsigned int i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        RTCRayHit rayhit = rtcGetRayHitFromRayHitN(args->rayhit, args->N, i);
        rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;  // tells a hit from a miss below
        accel.intersect1(rayhit);
        if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        RTCRayN_tfar(RTCRayHitN_RayN(args->rayhit, args->N), args->N, i) = rayhit.ray.tfar;
        rtcCopyHitToHitN(RTCRayHitN_HitN(args->rayhit, args->N), &rayhit.hit, args->N, i);
    }
}

void occluded_callback(const RTCOccludedFunctionNArguments* args) {
    const EmbreeAccel& accel = accel_of(args->geometryUserPtr);
    if (args->N == 1) {
        if (args->valid[0] != 0) accel.occluded1(*reinterpret_cast<RTCRay*>(args->ray));
        return;
    }
    for (unsigned int i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        RTCRay ray = rtcGetRayFromRayN(args->ray, args->N, i);
        accel.occluded1(ray);
        RTCRayN_tfar(args->ray, args->N, i) = ray.tfar;
    }
}

}  // namespace

EmbreeUserGeometryScene::EmbreeUserGeometryScene(const EmbreeAccel& accel) : accel_(accel) {
    const RTCDevice device = rtcGetSceneDevice(accel.rtc_scene());  // adds a reference
    if (device == nullptr) throw Error("EmbreeUserGeometryScene: rtcGetSceneDevice returned null");
    scene_ = rtcNewScene(device);
    geometry_ = scene_ == nullptr ? nullptr : rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcReleaseDevice(device);  // the scene and geometry hold their own references
    if (scene_ == nullptr || geometry_ == nullptr) {
        if (scene_ != nullptr) rtcReleaseScene(scene_);
        throw Error("EmbreeUserGeometryScene: Embree refused to create the scene or geometry");
    }
    // One primitive bounding the whole structure: Embree's own BVH is a single box, and every
    // ray that enters it is answered by the re-braided structure.
    rtcSetGeometryUserPrimitiveCount(geometry_, 1);
    rtcSetGeometryUserData(geometry_, const_cast<EmbreeAccel*>(&accel_));
    rtcSetGeometryBoundsFunction(geometry_, bounds_callback, nullptr);
    rtcSetGeometryIntersectFunction(geometry_, intersect_callback);
    rtcSetGeometryOccludedFunction(geometry_, occluded_callback);
    rtcCommitGeometry(geometry_);
    rtcAttachGeometry(scene_, geometry_);
    rtcCommitScene(scene_);
}

EmbreeUserGeometryScene::~EmbreeUserGeometryScene() {
    rtcReleaseGeometry(geometry_);
    rtcReleaseScene(scene_);
}

void EmbreeUserGeometryScene::update() {
    // Embree rebuilds a scene only when a geometry was committed since the last build.
    rtcCommitGeometry(geometry_);
    rtcCommitScene(scene_);
}

}  // namespace rebraid
