#pragma once

#include <cstdint>

#include "rebraid/bvh/object_bvh.h"

namespace rebraid {

/// What a ray entering an instance reads, in one record per instance: its mesh's BVH arrays
/// and the space the ray must be mapped into. Entering costs one lookup instead of a chain
/// (instance -> mesh -> ObjectBvh -> each array, plus the transform elsewhere).
struct InstanceTarget {
    /// `space` of instances placed by the identity: rays enter them unmapped.
    static constexpr std::uint32_t kWorldSpace = 0;

    ObjectBvhView bvh;
    /// kWorldSpace, or 1 + the index of the instance's world-to-object transform among the
    /// structure's distinct ones. Instances placed by the same transform share a space (a
    /// file's root rotation often places every mesh), so a ray mapped into it once serves
    /// all of them.
    std::uint32_t space = kWorldSpace;
};

}  // namespace rebraid
