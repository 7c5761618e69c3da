#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rebraid/core/bbox.h"
#include "rebraid/core/ray.h"

namespace rebraid {

/// `count` rays with origins uniform in `bounds` grown by a quarter of its extent on every
/// side, directions uniform on the sphere, tnear 0 and tfar inf. The same seed gives the
/// same rays on every machine and thread count (own generator, no std distributions).
/// A flat axis (zero extent) is padded by 1 on each side and an empty or non-finite box is
/// replaced by [-1, 1]^3, so any box gives valid rays.
std::vector<Ray> generate_random_rays(const BBox3f& bounds, std::size_t count, std::uint64_t seed);

}  // namespace rebraid
