#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rebraid/core/accel.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/scene.h"

namespace rebraid::cli {

/// How `rebraid bench` makes its rays.
struct BenchRaySettings {
    /// Primary rays (and as many diffuse rays): one per pixel of an image of `aspect`, filled
    /// row by row; the default is a 640 x 360 image.
    std::size_t ray_count = 640 * 360;
    /// Width / height of that image.
    float aspect = 16.0f / 9.0f;
    /// Seed of the diffuse directions; the same seed gives the same rays on any thread count.
    std::uint64_t seed = 1;
};

/// The two ray sets every structure of one bench run traces.
struct BenchRays {
    /// Camera rays from viewer::frame_scene's camera, one per pixel centre: coherent.
    std::vector<Ray> primary;
    /// Diffuse bounces: ray i starts at the hit point of the i-th hitting primary ray (cycling
    /// through them), lifted off the surface, with a cosine-distributed direction around the
    /// geometric normal facing the camera: incoherent. Empty when no primary ray hits.
    std::vector<Ray> diffuse;
    int image_width = 0;  ///< of the primary image (its last row may be partial)
    int image_height = 0;
    std::size_t primary_hit_count = 0;  ///< as `reference` answered
};

/// Makes the rays of `scene`, finding the primary hit points with `reference` (any structure
/// over `scene`; the bench uses embree-instanced, which fits every scene in memory). Throws
/// rebraid::Error for a scene without triangles or a ray count of 0.
BenchRays make_bench_rays(const Scene& scene, const Accel& reference,
                          const BenchRaySettings& settings);

}  // namespace rebraid::cli
