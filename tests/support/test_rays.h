#pragma once

// Rays of every kind a structure must answer as Embree does, not only the random unit rays
// over [0, inf) of generate_random_rays: unnormalised directions (t in units of the
// direction), directions with zero components (the box test's reciprocals), segments that
// end before the closest hit (often inside an instance the ray has entered, through one or
// several of its BRefs), segments that start past it (tnear > 0), and random finite
// segments.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "rebraid/core/accel.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/random.h"
#include "rebraid/generators/random_rays.h"

namespace rebraid::test {

/// The kinds of rays varied_rays() mixes, in the order it cycles through them.
enum class RayFamily : std::uint32_t {
    unit_unbounded,   ///< generate_random_rays as it is
    unnormalised,     ///< direction scaled by 0.01 .. 100
    axis_aligned,     ///< one or two direction components exactly zero
    ends_before_hit,  ///< tfar a random fraction of the way to the closest hit
    starts_past_hit,  ///< tnear just past the closest hit
    finite_segment,   ///< random tnear > 0 and finite tfar
    count
};

inline constexpr std::uint32_t kRayFamilyCount = std::uint32_t(RayFamily::count);

/// The family of ray `index` of varied_rays().
inline RayFamily ray_family(std::size_t index) {
    return RayFamily(std::uint32_t(index % kRayFamilyCount));
}

/// `count` rays over `bounds`, cycling through the families of RayFamily (ray i is of family
/// ray_family(i)). `reference` (any structure over the scene, usually Embree's) finds the
/// closest hits the segment families are cut at. Same seed, same rays.
inline std::vector<Ray> varied_rays(const Accel& reference, const BBox3f& bounds, std::size_t count,
                                    std::uint64_t seed) {
    std::vector<Ray> rays = generate_random_rays(bounds, count, seed);
    Random random(seed ^ 0x9e3779b97f4a7c15ull);
    const Vec3f extent = bounds.extent();
    const float diagonal =
        std::isfinite(length(extent)) && length(extent) > 0.0f ? length(extent) : 1.0f;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        Ray& ray = rays[i];
        switch (ray_family(i)) {
            case RayFamily::unit_unbounded:
                break;
            case RayFamily::unnormalised:
                ray.dir = ray.dir * std::exp2(random.next_float(-6.6f, 6.6f));
                break;
            case RayFamily::axis_aligned: {
                // Zero one component (a ray parallel to a coordinate plane) or two (along an
                // axis); the remaining ones keep their sign.
                const std::uint32_t keep = random.next_below(3);
                const bool along_axis = random.next_below(2) == 1;
                for (std::uint32_t axis = 0; axis < 3; ++axis)
                    if (along_axis ? axis != keep : axis == keep) ray.dir[int(axis)] = 0.0f;
                if (length(ray.dir) == 0.0f) ray.dir[int(keep)] = 1.0f;
                break;
            }
            case RayFamily::ends_before_hit: {
                const Hit hit = reference.intersect(ray);
                ray.tfar = hit.is_hit() ? hit.t * random.next_float(0.3f, 0.999f)
                                        : diagonal * random.next_float(0.1f, 1.0f);
                break;
            }
            case RayFamily::starts_past_hit: {
                const Hit hit = reference.intersect(ray);
                ray.tnear = hit.is_hit() ? hit.t * 1.001f + 1e-4f * diagonal
                                         : diagonal * random.next_float(0.0f, 0.5f);
                break;
            }
            case RayFamily::finite_segment:
                ray.tnear = diagonal * random.next_float(0.0f, 0.5f);
                ray.tfar = ray.tnear + diagonal * random.next_float(0.05f, 1.0f);
                break;
            case RayFamily::count:
                break;
        }
    }
    return rays;
}

}  // namespace rebraid::test
