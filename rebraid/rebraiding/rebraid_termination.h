#pragma once

#include <span>

#include "rebraid/rebraiding/bref.h"

namespace rebraid {

/// Paper §4.4, second rule (the first, one instance only, is OpeningScan::is_single_instance
/// in bref_opening.h), for segments of a few BRefs: true when the boxes overlap little,
/// i.e. every pairwise intersection has at most `max_fraction` of the surface area of the
/// smaller of the two boxes. Such a segment stops opening even though its instances differ.
bool overlaps_little(std::span<const BuildPrim> prims, float max_fraction);

}  // namespace rebraid
