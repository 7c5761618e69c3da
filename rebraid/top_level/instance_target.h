#pragma once

#include <cstdint>

#include "rebraid/core/transform.h"

namespace rebraid {

/// What a ray entering an instance reads, in one cache line per instance: the transform into
/// its object space, its mesh (whose BVH arrays InstancedAccel::object_views() holds, few and
/// hot in cache) and its space's id. Entering costs one line instead of a chain (instance ->
/// mesh -> ObjectBvh -> each array, and the transform in an array of its own: on a million
/// instances each of those was a miss of its own).
struct alignas(64) InstanceTarget {
    /// `space` of instances placed by the identity: rays enter them unmapped.
    static constexpr std::uint32_t kWorldSpace = 0;

    /// World to object; the identity for kWorldSpace.
    AffineTransform to_object = AffineTransform::identity();
    /// Index into InstancedAccel::object_views().
    std::uint32_t mesh = 0;
    /// kWorldSpace, or 1 + the number of the first instance placed by a transform of the
    /// same bits. Instances placed by the same transform share a space (a file's root
    /// rotation often places every mesh), so a ray mapped into it once serves all of them.
    std::uint32_t space = kWorldSpace;
};

static_assert(sizeof(InstanceTarget) == 64);

}  // namespace rebraid
