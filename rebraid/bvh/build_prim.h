#pragma once

#include <cstdint>

#include "rebraid/core/bbox.h"

namespace rebraid {

/// What the binned-SAH builder sorts: a box standing for `weight` primitives. For object
/// BVHs one triangle (weight 1); for top levels an instance or a BRef, whose weight is its
/// (estimated) primitive count (re-braiding paper §4.3).
struct BuildPrim {
    BBox3f bounds;
    std::uint32_t id = 0;      ///< index into the caller's primitive list
    std::uint32_t weight = 1;  ///< primitives this box stands for, for the SAH
    Vec3f centroid() const { return bounds.center(); }
};

}  // namespace rebraid
