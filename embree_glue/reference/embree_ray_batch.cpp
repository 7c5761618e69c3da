#include "embree_glue/reference/embree_ray_batch.h"

#include <functional>

#include "embree_glue/reference/embree_dynamic_scene.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"

namespace rebraid::glue {

bool EmbreeRayBatch::serves(const Accel& accel) {
    return dynamic_cast<const EmbreeFlatAccel*>(&accel) != nullptr ||
           dynamic_cast<const EmbreeInstancedAccel*>(&accel) != nullptr ||
           dynamic_cast<const EmbreeDynamicAccel*>(&accel) != nullptr;
}

EmbreeRayBatch::EmbreeRayBatch(const Accel& accel, std::span<const Ray> rays) {
    // Which rays reach Embree: each structure's own rule (and its errors).
    std::function<bool(const Ray&)> is_traced;
    if (const auto* flat = dynamic_cast<const EmbreeFlatAccel*>(&accel)) {
        scene_ = flat->rtc_scene();
        is_traced = [limits = flat->ray_limits()](const Ray& ray) {
            return is_traced_by_embree(ray, limits, "EmbreeFlatAccel");
        };
    } else if (const auto* instanced = dynamic_cast<const EmbreeInstancedAccel*>(&accel)) {
        scene_ = instanced->rtc_scene();
        instance_id_is_inst_id_ = true;
        is_traced = [limits = instanced->ray_limits()](const Ray& ray) {
            return is_traced_by_embree(ray, limits, "EmbreeInstancedAccel");
        };
    } else if (const auto* dynamic = dynamic_cast<const EmbreeDynamicAccel*>(&accel)) {
        scene_ = dynamic->rtc_scene();
        instance_id_is_inst_id_ = dynamic->names_instances_by_inst_id();
        is_traced = &EmbreeDynamicAccel::is_traced_by_embree;
    } else {
        throw Error("EmbreeRayBatch: the structure is not one of Embree's reference structures");
    }
    rays_.resize(rays.size());
    input_tfar_.resize(rays.size());
    is_traced_.resize(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) {
        is_traced_[i] = is_traced(rays[i]) ? 1 : 0;
        rays_[i].ray = to_embree_ray(rays[i]);
        input_tfar_[i] = rays[i].tfar;
        rays_[i].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rays_[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
}

void EmbreeRayBatch::intersect(std::size_t begin, std::size_t end) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t i = begin; i < end; ++i) {
        RTCRayHit& rayhit = rays_[i];
        rayhit.ray.tfar = input_tfar_[i];
        rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        if (is_traced_[i]) rtcIntersect1(scene_, &context, &rayhit);
    }
}

void EmbreeRayBatch::occlude(std::size_t begin, std::size_t end) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t i = begin; i < end; ++i) {
        RTCRay& ray = rays_[i].ray;
        ray.tfar = input_tfar_[i];
        if (is_traced_[i]) rtcOccluded1(scene_, &context, &ray);
    }
}

}  // namespace rebraid::glue
