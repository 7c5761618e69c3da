#pragma once

#include <embree3/rtcore.h>

#include "embree_glue/reference/embree_device.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/transform.h"

namespace rebraid::glue {

/// Embree's name for `quality`.
RTCBuildQuality to_embree_quality(EmbreeBuildQuality quality);

/// `ray` as Embree's single ray: visible to every geometry, time 0, no id or flags.
RTCRay to_embree_ray(const Ray& ray);

/// Embree's single ray as ours: origin, direction and the [tnear, tfar] interval.
inline Ray from_embree_ray(const RTCRay& ray) {  // inline: on every traced ray's path
    Ray out;
    out.org = {ray.org_x, ray.org_y, ray.org_z};
    out.dir = {ray.dir_x, ray.dir_y, ray.dir_z};
    out.tnear = ray.tnear;
    out.tfar = ray.tfar;
    return out;
}

/// Embree's closest hit of `ray` in `scene` (rtcIntersect1), a miss when nothing is hit; the
/// hit's instance id is Embree's instID[0] when `instance_id_is_inst_id`, else its geomID
/// (a flattened scene has one geometry per instance).
Hit embree_closest_hit(RTCScene scene, const Ray& ray, bool instance_id_is_inst_id);

/// Whether anything in `scene` blocks `ray` (rtcOccluded1).
bool embree_is_occluded(RTCScene scene, const Ray& ray);

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
