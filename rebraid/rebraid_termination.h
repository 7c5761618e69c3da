#pragma once

#include <span>

#include "rebraid/bref.h"

namespace rebraid {

/// Paper §4.4, first rule: when every BRef of a segment belongs to one instance, opening
/// cannot improve on that object's own (already good) BVH; the segment and its whole subtree
/// stop opening. Two instances of one mesh are different instances.
bool all_same_instance(std::span<const BuildPrim> prims, std::span<const BRefTarget> targets);

/// Paper §4.4, second rule, for segments of a few BRefs: true when the boxes overlap little,
/// i.e. every pairwise intersection has at most `max_fraction` of the surface area of the
/// smaller of the two boxes. Such a segment stops opening even though its instances differ.
bool overlaps_little(std::span<const BuildPrim> prims, float max_fraction);

}  // namespace rebraid
