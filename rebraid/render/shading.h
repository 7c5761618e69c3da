#pragma once

#include "rebraid/core/scene.h"
#include "rebraid/core/types.h"

namespace rebraid::viewer {

/// Unit geometric normal of triangle `prim_id` of instance `instance_id`, in world space
/// (corners transformed by the instance, then crossed; mirrored instances flip it). The
/// zero vector for a degenerate triangle. Ids must be valid for `scene`.
Vec3f world_geometric_normal(const Scene& scene, InstanceId instance_id, PrimId prim_id);

/// A soft colour per instance, from a hash of its id, so neighbouring instances differ.
Vec3f instance_tint(InstanceId instance_id);

/// Background for rays that leave the scene: a gradient from a pale horizon to a blue zenith
/// along `world_up` (both unit vectors).
Vec3f sky_colour(Vec3f direction, Vec3f world_up);

/// A direction in the hemisphere around the unit `normal`, cosine-distributed, from two
/// uniform numbers in [0, 1). Unit length.
Vec3f sample_cosine_hemisphere(Vec3f normal, float u1, float u2);

}  // namespace rebraid::viewer
