// The preload library's Embree functions: the ray queries. Each asks PreloadScenes whether
// rebraid serves the scene; if not, or when the call carries an intersection filter in its
// context (which only Embree can call at the right moments), it forwards to Embree unchanged.
// Packets and streams are answered ray by ray with Embree's conventions: a packet's lanes
// whose valid entry is not -1 are left untouched (where Embree has packet kernels of that width;
// else it traces the packet as a stream), and in streams a ray with tnear > tfar is inactive.

#include <embree3/rtcore.h>

#include <cstddef>
#include <cstdio>
#include <exception>

#include "embree_glue/dropin/embree_accel.h"
#include "embree_glue/dropin/embree_interposer.h"
#include "embree_glue/dropin/embree_next_definition.h"
#include "embree_glue/dropin/never_destroyed.h"
#include "embree_glue/preload/preload_scenes.h"
#include "embree_glue/preload/preload_settings.h"

namespace {

using rebraid::EmbreeAccel;
using namespace rebraid::glue;

/// Null when the preload is off (REBRAID_PRELOAD=0 or a bad setting): every query forwards.
PreloadScenes* g_scenes = nullptr;

/// Reads the settings and installs the observer when the library is loaded, before the
/// application's first Embree call.
[[gnu::constructor]] void start_preload() {
    try {
        const PreloadSettings settings = read_preload_settings(process_environment);
        if (!settings.is_enabled) return;
        static NeverDestroyed<PreloadScenes> scenes(settings);
        g_scenes = &scenes.get();
        set_interposer_observer(g_scenes);
    } catch (const std::exception& error) {
        std::fprintf(stderr, "rebraid preload: %s; Embree serves every scene\n", error.what());
    }
}

/// Whether a query with `context` is Embree's to answer whatever the scene.
bool context_needs_embree(const RTCIntersectContext* context) noexcept {
    if (context == nullptr) return false;
    // Embree calls a context's filter function, which only it can call at the right moments.
    // A ray the application traces from its own instancing (a user geometry's intersect
    // function tracing another scene with the instance on the context's stack): Embree reports
    // and limits instance levels from that stack.
    return context->filter != nullptr || context->instID[0] != RTC_INVALID_GEOMETRY_ID;
}

/// How a query on `scene` with `context` is answered: rebraid's structure, or Embree (null).
const EmbreeAccel* served(RTCScene scene, const RTCIntersectContext* context) noexcept {
    if (g_scenes == nullptr || context_needs_embree(context)) return nullptr;
    return g_scenes->served(scene).accel;
}

/// served's answer where it is at hand: rebraid's structure when this thread's last answer
/// for `scene` stands and names one; else null, and the caller asks served out of line. The
/// single-ray queries then make no call before the structure's own on their common path, and
/// save no registers for one.
const EmbreeAccel* served_at_hand(RTCScene scene, const RTCIntersectContext* context) noexcept {
    // Only a PreloadScenes gives answers: without one (g_scenes null) none stands.
    if (context_needs_embree(context)) return nullptr;
    const ServedScene* last = PreloadScenes::last_answer(scene);
    return last != nullptr ? last->accel : nullptr;
}

#define REBRAID_REAL(name) static auto* const real = next_definition<decltype(name)>(#name)

// ---- Ray layouts: one ray out of, and its answer back into, each of Embree's layouts -------

/// Lane `i` of a packet or stream of N rays in SOA layout (RTCRayHitN, RTCRayHit4/8/16).
void intersect_lane(const EmbreeAccel& accel, RTCRayHitN* rays, unsigned int n, unsigned int i) {
    RTCRayHit rayhit = rtcGetRayHitFromRayHitN(rays, n, i);
    if (!(rayhit.ray.tnear <= rayhit.ray.tfar)) return;
    const unsigned int missed = rayhit.hit.geomID;
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    accel.intersect1(rayhit);
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        rayhit.hit.geomID = missed;
        return;
    }
    RTCRayN_tfar(RTCRayHitN_RayN(rays, n), n, i) = rayhit.ray.tfar;
    rtcCopyHitToHitN(RTCRayHitN_HitN(rays, n), &rayhit.hit, n, i);
}

void occlude_lane(const EmbreeAccel& accel, RTCRayN* rays, unsigned int n, unsigned int i) {
    RTCRay ray = rtcGetRayFromRayN(rays, n, i);
    accel.occluded1(ray);
    RTCRayN_tfar(rays, n, i) = ray.tfar;
}

/// The lanes of a packet of `n` rays Embree traces: those `valid` marks -1 where Embree has
/// packet kernels of that width, else (it traces the packet as a stream) every lane, each
/// then active when tnear <= tfar (EmbreeAccel::has_native_packets). Null: every lane.
const int* active_lanes(const EmbreeAccel& accel, const int* valid, unsigned int n) {
    return accel.has_native_packets(n) ? valid : nullptr;
}

template <typename Packet>
void intersect_packet(const EmbreeAccel& accel, const int* valid, Packet* packet, unsigned int n) {
    valid = active_lanes(accel, valid, n);
    for (unsigned int i = 0; i < n; ++i)
        if (valid == nullptr || valid[i] == -1)
            intersect_lane(accel, reinterpret_cast<RTCRayHitN*>(packet), n, i);
}

template <typename Packet>
void occlude_packet(const EmbreeAccel& accel, const int* valid, Packet* packet, unsigned int n) {
    valid = active_lanes(accel, valid, n);
    for (unsigned int i = 0; i < n; ++i)
        if (valid == nullptr || valid[i] == -1)
            occlude_lane(accel, reinterpret_cast<RTCRayN*>(packet), n, i);
}

/// Lane `i` of a stream in pointer-SOA layout (RTCRayHitNp).
void intersect_lane(const EmbreeAccel& accel, const RTCRayHitNp& rays, unsigned int i) {
    RTCRayHit rayhit{};
    RTCRay& ray = rayhit.ray;
    ray.org_x = rays.ray.org_x[i];
    ray.org_y = rays.ray.org_y[i];
    ray.org_z = rays.ray.org_z[i];
    ray.tnear = rays.ray.tnear[i];
    ray.dir_x = rays.ray.dir_x[i];
    ray.dir_y = rays.ray.dir_y[i];
    ray.dir_z = rays.ray.dir_z[i];
    ray.time = rays.ray.time[i];
    ray.tfar = rays.ray.tfar[i];
    ray.mask = rays.ray.mask[i];
    ray.id = rays.ray.id[i];
    ray.flags = rays.ray.flags[i];
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    accel.intersect1(rayhit);
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
    rays.ray.tfar[i] = ray.tfar;
    rays.hit.Ng_x[i] = rayhit.hit.Ng_x;
    rays.hit.Ng_y[i] = rayhit.hit.Ng_y;
    rays.hit.Ng_z[i] = rayhit.hit.Ng_z;
    rays.hit.u[i] = rayhit.hit.u;
    rays.hit.v[i] = rayhit.hit.v;
    rays.hit.primID[i] = rayhit.hit.primID;
    rays.hit.geomID[i] = rayhit.hit.geomID;
    for (unsigned int level = 0; level < RTC_MAX_INSTANCE_LEVEL_COUNT; ++level)
        rays.hit.instID[level][i] = rayhit.hit.instID[level];
}

void occlude_lane(const EmbreeAccel& accel, const RTCRayNp& rays, unsigned int i) {
    RTCRay ray{};
    ray.org_x = rays.org_x[i];
    ray.org_y = rays.org_y[i];
    ray.org_z = rays.org_z[i];
    ray.tnear = rays.tnear[i];
    ray.dir_x = rays.dir_x[i];
    ray.dir_y = rays.dir_y[i];
    ray.dir_z = rays.dir_z[i];
    ray.time = rays.time[i];
    ray.tfar = rays.tfar[i];
    ray.mask = rays.mask[i];
    ray.id = rays.id[i];
    ray.flags = rays.flags[i];
    accel.occluded1(ray);
    rays.tfar[i] = ray.tfar;
}

template <typename T>
T* at_stride(T* first, std::size_t byte_stride, unsigned int index) {
    return reinterpret_cast<T*>(reinterpret_cast<std::byte*>(first) + byte_stride * index);
}

/// rtcIntersect1 past served_at_hand: asks served, and forwards to Embree where it answers.
[[gnu::noinline]] void intersect1_asking(RTCScene scene, RTCIntersectContext* context,
                                         RTCRayHit* rayhit) {
    if (const EmbreeAccel* accel = served(scene, context)) return accel->intersect1(*rayhit);
    REBRAID_REAL(rtcIntersect1);
    call_real(real, scene, context, rayhit);
}

/// rtcOccluded1 past served_at_hand, as intersect1_asking.
[[gnu::noinline]] void occluded1_asking(RTCScene scene, RTCIntersectContext* context, RTCRay* ray) {
    if (const EmbreeAccel* accel = served(scene, context)) return accel->occluded1(*ray);
    REBRAID_REAL(rtcOccluded1);
    call_real(real, scene, context, ray);
}

}  // namespace

// The library is compiled with hidden visibility; Embree's names are its interface.
#pragma GCC visibility push(default)
extern "C" {

// ---- Single rays ---------------------------------------------------------------------------

void rtcIntersect1(RTCScene scene, RTCIntersectContext* context, RTCRayHit* rayhit) {
    if (const EmbreeAccel* accel = served_at_hand(scene, context))
        return accel->intersect1(*rayhit);
    intersect1_asking(scene, context, rayhit);
}

void rtcOccluded1(RTCScene scene, RTCIntersectContext* context, RTCRay* ray) {
    if (const EmbreeAccel* accel = served_at_hand(scene, context)) return accel->occluded1(*ray);
    occluded1_asking(scene, context, ray);
}

// ---- Packets -------------------------------------------------------------------------------

void rtcIntersect4(const int* valid, RTCScene scene, RTCIntersectContext* context,
                   RTCRayHit4* rayhit) {
    if (const EmbreeAccel* accel = served(scene, context))
        return intersect_packet(*accel, valid, rayhit, 4);
    REBRAID_REAL(rtcIntersect4);
    call_real(real, valid, scene, context, rayhit);
}

void rtcIntersect8(const int* valid, RTCScene scene, RTCIntersectContext* context,
                   RTCRayHit8* rayhit) {
    if (const EmbreeAccel* accel = served(scene, context))
        return intersect_packet(*accel, valid, rayhit, 8);
    REBRAID_REAL(rtcIntersect8);
    call_real(real, valid, scene, context, rayhit);
}

void rtcIntersect16(const int* valid, RTCScene scene, RTCIntersectContext* context,
                    RTCRayHit16* rayhit) {
    if (const EmbreeAccel* accel = served(scene, context))
        return intersect_packet(*accel, valid, rayhit, 16);
    REBRAID_REAL(rtcIntersect16);
    call_real(real, valid, scene, context, rayhit);
}

void rtcOccluded4(const int* valid, RTCScene scene, RTCIntersectContext* context, RTCRay4* ray) {
    if (const EmbreeAccel* accel = served(scene, context))
        return occlude_packet(*accel, valid, ray, 4);
    REBRAID_REAL(rtcOccluded4);
    call_real(real, valid, scene, context, ray);
}

void rtcOccluded8(const int* valid, RTCScene scene, RTCIntersectContext* context, RTCRay8* ray) {
    if (const EmbreeAccel* accel = served(scene, context))
        return occlude_packet(*accel, valid, ray, 8);
    REBRAID_REAL(rtcOccluded8);
    call_real(real, valid, scene, context, ray);
}

void rtcOccluded16(const int* valid, RTCScene scene, RTCIntersectContext* context, RTCRay16* ray) {
    if (const EmbreeAccel* accel = served(scene, context))
        return occlude_packet(*accel, valid, ray, 16);
    REBRAID_REAL(rtcOccluded16);
    call_real(real, valid, scene, context, ray);
}

// ---- Streams -------------------------------------------------------------------------------

void rtcIntersect1M(RTCScene scene, RTCIntersectContext* context, RTCRayHit* rayhit, unsigned int M,
                    size_t byteStride) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int i = 0; i < M; ++i) accel->intersect1(*at_stride(rayhit, byteStride, i));
        return;
    }
    REBRAID_REAL(rtcIntersect1M);
    call_real(real, scene, context, rayhit, M, byteStride);
}

void rtcOccluded1M(RTCScene scene, RTCIntersectContext* context, RTCRay* ray, unsigned int M,
                   size_t byteStride) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int i = 0; i < M; ++i) accel->occluded1(*at_stride(ray, byteStride, i));
        return;
    }
    REBRAID_REAL(rtcOccluded1M);
    call_real(real, scene, context, ray, M, byteStride);
}

void rtcIntersect1Mp(RTCScene scene, RTCIntersectContext* context, RTCRayHit** rayhit,
                     unsigned int M) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int i = 0; i < M; ++i) accel->intersect1(*rayhit[i]);
        return;
    }
    REBRAID_REAL(rtcIntersect1Mp);
    call_real(real, scene, context, rayhit, M);
}

void rtcOccluded1Mp(RTCScene scene, RTCIntersectContext* context, RTCRay** ray, unsigned int M) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int i = 0; i < M; ++i) accel->occluded1(*ray[i]);
        return;
    }
    REBRAID_REAL(rtcOccluded1Mp);
    call_real(real, scene, context, ray, M);
}

void rtcIntersectNM(RTCScene scene, RTCIntersectContext* context, RTCRayHitN* rayhit,
                    unsigned int N, unsigned int M, size_t byteStride) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int m = 0; m < M; ++m)
            intersect_packet(*accel, nullptr, at_stride(rayhit, byteStride, m), N);
        return;
    }
    REBRAID_REAL(rtcIntersectNM);
    call_real(real, scene, context, rayhit, N, M, byteStride);
}

void rtcOccludedNM(RTCScene scene, RTCIntersectContext* context, RTCRayN* ray, unsigned int N,
                   unsigned int M, size_t byteStride) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int m = 0; m < M; ++m)
            occlude_packet(*accel, nullptr, at_stride(ray, byteStride, m), N);
        return;
    }
    REBRAID_REAL(rtcOccludedNM);
    call_real(real, scene, context, ray, N, M, byteStride);
}

void rtcIntersectNp(RTCScene scene, RTCIntersectContext* context, const RTCRayHitNp* rayhit,
                    unsigned int N) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int i = 0; i < N; ++i) intersect_lane(*accel, *rayhit, i);
        return;
    }
    REBRAID_REAL(rtcIntersectNp);
    call_real(real, scene, context, rayhit, N);
}

void rtcOccludedNp(RTCScene scene, RTCIntersectContext* context, const RTCRayNp* ray,
                   unsigned int N) {
    if (const EmbreeAccel* accel = served(scene, context)) {
        for (unsigned int i = 0; i < N; ++i) occlude_lane(*accel, *ray, i);
        return;
    }
    REBRAID_REAL(rtcOccludedNp);
    call_real(real, scene, context, ray, N);
}

}  // extern "C"
#pragma GCC visibility pop
