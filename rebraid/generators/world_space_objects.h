#pragma once

#include <cstdint>

#include "rebraid/core/scene.h"

namespace rebraid {

/// The same geometry as `scene` with its instances turned into objects in world space: object
/// k (mesh k, placed by instance k with the identity transform) holds the triangles of
/// instances [k * instances_per_object, (k + 1) * instances_per_object), in that order, with
/// their transforms applied to the vertices. With 1 (the default) every instance becomes an
/// object of its own. This is how renderers hold scenes that
/// are not instanced (one BVH per object, objects placed where they stand): the paper's
/// Powerplant, Crown and Boeing (Benthin et al. 2017, §6 and Figure 1), where long or large
/// objects make world-space boxes overlap. Mesh names get the object number appended.
/// Throws rebraid::Error for instances_per_object = 0 or an object past 2^32 - 1 vertices.
Scene bake_instances_into_world_space(const Scene& scene, std::uint32_t instances_per_object = 1);

}  // namespace rebraid
