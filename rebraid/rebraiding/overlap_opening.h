#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/core/bbox.h"
#include "rebraid/rebraiding/bref.h"

namespace rebraid {

/// Overlap-driven opening (beyond the paper): flags the BRefs of a segment whose box lies at least
/// `min_fraction` inside regions that BRefs of other instances also reach, i.e. where opening
/// could let the top level regroup parts of different instances. Estimated on a grid of at
/// most 8 x 8 x 8 cells over `segment_bounds` (about one cell per BRef): a cell counts as
/// shared when BRefs of two or more instances touch it, and a BRef's fraction is the share
/// of its box's volume (lengths along flat axes count as whole) lying in shared cells. Linear
/// in the BRefs times the cells each covers; independent of their order.
std::vector<std::uint8_t> select_overlapping(std::span<const BuildPrim> prims,
                                             std::span<const BRefTarget> targets,
                                             const BBox3f& segment_bounds, float min_fraction);

}  // namespace rebraid
