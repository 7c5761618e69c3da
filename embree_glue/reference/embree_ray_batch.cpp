#include "embree_glue/reference/embree_ray_batch.h"

#include <functional>
#include <optional>

#include "embree_glue/reference/embree_dynamic_scene.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"

namespace rebraid::glue {

namespace {

/// What a batch needs of one of Embree's reference structures: its scene, how its hits name
/// instances, and which rays it hands to Embree (its own rule and errors).
struct BatchTarget {
    RTCScene scene = nullptr;
    bool instance_id_is_inst_id = false;
    std::function<bool(const Ray&)> is_traced;
};

/// The one list of structures a batch serves; empty for any other.
std::optional<BatchTarget> batch_target(const Accel& accel) {
    if (const auto* flat = dynamic_cast<const EmbreeFlatAccel*>(&accel))
        return BatchTarget{flat->rtc_scene(), false, [limits = flat->ray_limits()](const Ray& ray) {
                               return is_traced_by_embree(ray, limits, "EmbreeFlatAccel");
                           }};
    if (const auto* instanced = dynamic_cast<const EmbreeInstancedAccel*>(&accel))
        return BatchTarget{instanced->rtc_scene(), true,
                           [limits = instanced->ray_limits()](const Ray& ray) {
                               return is_traced_by_embree(ray, limits, "EmbreeInstancedAccel");
                           }};
    if (const auto* dynamic = dynamic_cast<const EmbreeDynamicAccel*>(&accel))
        return BatchTarget{dynamic->rtc_scene(), dynamic->names_instances_by_inst_id(),
                           &EmbreeDynamicAccel::is_traced_by_embree};
    return std::nullopt;
}

}  // namespace

bool EmbreeRayBatch::serves(const Accel& accel) {
    return batch_target(accel).has_value();
}

EmbreeRayBatch::EmbreeRayBatch(const Accel& accel, std::span<const Ray> rays) {
    std::optional<BatchTarget> target = batch_target(accel);
    if (!target)
        throw Error("EmbreeRayBatch: the structure is not one of Embree's reference structures");
    scene_ = target->scene;
    instance_id_is_inst_id_ = target->instance_id_is_inst_id;
    rays_.resize(rays.size());
    input_tfar_.resize(rays.size());
    is_traced_.resize(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) {
        is_traced_[i] = target->is_traced(rays[i]) ? 1 : 0;
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
