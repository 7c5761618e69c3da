#include "rebraid/generators/random_rays.h"

#include <cmath>
#include <limits>
#include <numbers>

#include "rebraid/core/random.h"

namespace rebraid {
namespace {

/// The box origins are drawn from: `bounds` grown by a quarter of its extent per side, with
/// degenerate input made usable (see random_rays.h).
BBox3f origin_box(const BBox3f& bounds) {
    if (bounds.is_empty() || !is_finite(bounds.min) || !is_finite(bounds.max))
        return {{-1.0f, -1.0f, -1.0f}, {1.0f, 1.0f, 1.0f}};
    BBox3f box = bounds;
    for (int axis = 0; axis < 3; ++axis) {
        const float extent = box.max[axis] - box.min[axis];
        const float margin = extent > 0.0f ? 0.25f * extent : 1.0f;
        box.min[axis] -= margin;
        box.max[axis] += margin;
    }
    return box;
}

/// Uniform direction on the unit sphere (Archimedes: z uniform in [-1, 1], azimuth uniform).
Vec3f random_unit_direction(Random& random) {
    const double z = 2.0 * static_cast<double>(random.next_float01()) - 1.0;
    const double phi = 2.0 * std::numbers::pi * static_cast<double>(random.next_float01());
    const double r = std::sqrt(std::fmax(0.0, 1.0 - z * z));
    return {static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)),
            static_cast<float>(z)};
}

}  // namespace

std::vector<Ray> generate_random_rays(const BBox3f& bounds, std::size_t count, std::uint64_t seed) {
    const BBox3f box = origin_box(bounds);
    const Vec3f extent = box.extent();
    Random random(seed);
    std::vector<Ray> rays(count);
    for (Ray& ray : rays) {
        // Fixed draw order (x, y, z, then direction) keeps the stream identical everywhere.
        const float ux = random.next_float01();
        const float uy = random.next_float01();
        const float uz = random.next_float01();
        ray.org = {box.min.x + extent.x * ux, box.min.y + extent.y * uy, box.min.z + extent.z * uz};
        ray.dir = random_unit_direction(random);
        ray.tnear = 0.0f;
        ray.tfar = std::numeric_limits<float>::infinity();
    }
    return rays;
}

}  // namespace rebraid
