#pragma once

#include <embree3/rtcore.h>

#include <limits>

#include "embree_glue/reference/embree_device.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/transform.h"

namespace rebraid::glue {

/// Embree's name for `quality`.
RTCBuildQuality to_embree_quality(EmbreeBuildQuality quality);

/// `ray` as Embree's single ray: visible to every geometry, time 0, no id or flags.
inline RTCRay to_embree_ray(const Ray& ray) {  // inline, as the two queries below
    RTCRay out;
    out.org_x = ray.org.x;
    out.org_y = ray.org.y;
    out.org_z = ray.org.z;
    out.tnear = ray.tnear;
    out.dir_x = ray.dir.x;
    out.dir_y = ray.dir.y;
    out.dir_z = ray.dir.z;
    out.time = 0.0f;
    out.tfar = ray.tfar;
    out.mask = std::numeric_limits<unsigned int>::max();  // every geometry is visible
    out.id = 0;
    out.flags = 0;
    return out;
}

/// Embree's single ray as ours: origin, direction and the [tnear, tfar] interval.
inline Ray from_embree_ray(const RTCRay& ray) {  // inline: on every traced ray's path
    Ray out;
    out.org = {ray.org_x, ray.org_y, ray.org_z};
    out.dir = {ray.dir_x, ray.dir_y, ray.dir_z};
    out.tnear = ray.tnear;
    out.tfar = ray.tfar;
    return out;
}

/// The hit Embree wrote into `rayhit`, in the project's terms: a miss when no geometry was hit;
/// the instance id is Embree's instID[0] when `instance_id_is_inst_id`, else its geomID (a
/// flattened scene has one geometry per instance).
inline Hit hit_from_embree(const RTCRayHit& rayhit, bool instance_id_is_inst_id) {
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return Hit{};
    Hit hit;
    hit.t = rayhit.ray.tfar;
    hit.instance_id = instance_id_is_inst_id ? rayhit.hit.instID[0] : rayhit.hit.geomID;
    hit.prim_id = rayhit.hit.primID;
    hit.u = rayhit.hit.u;
    hit.v = rayhit.hit.v;
    return hit;
}

/// Embree's closest hit of `ray` in `scene` (rtcIntersect1), as hit_from_embree gives it.
/// Inline, with the ray set up as an application sets it up: each instruction around the
/// call counts against Embree where a query through the Accel interface is timed (the
/// benchmarks time Embree on rays already in its layout: EmbreeRayBatch).
inline Hit embree_closest_hit(RTCScene scene, const Ray& ray, bool instance_id_is_inst_id) {
    // Only the hit's ids are inputs; Embree writes the rest on a hit, the only case they are
    // read.
    RTCRayHit rayhit;
    rayhit.ray = to_embree_ray(ray);
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(scene, &context, &rayhit);
    return hit_from_embree(rayhit, instance_id_is_inst_id);
}

/// Whether anything in `scene` blocks `ray` (rtcOccluded1).
inline bool embree_is_occluded(RTCScene scene, const Ray& ray) {
    RTCRay embree_ray = to_embree_ray(ray);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcOccluded1(scene, &context, &embree_ray);
    // Embree marks an occluded ray by setting tfar to -inf.
    return embree_ray.tfar == -std::numeric_limits<float>::infinity();
}

/// Writes `mesh`'s positions, mapped by `to_world` (object space when null), into `geometry`'s
/// vertex buffer, which must hold as many vertices.
void write_vertices(RTCGeometry geometry, const Mesh& mesh, const AffineTransform* to_world);

/// A new triangle geometry holding `mesh` (its vertices mapped by `to_world`, object space
/// when null), built at `quality`, committed and attached to `scene` as `geom_id`. Returns the
/// geometry, borrowed from the scene (which holds the only reference).
RTCGeometry attach_triangle_mesh(EmbreeDevice& device, RTCScene scene, const Mesh& mesh,
                                 const AffineTransform* to_world, unsigned int geom_id,
                                 RTCBuildQuality quality);

}  // namespace rebraid::glue
