#pragma once

#include <cstdint>
#include <functional>

#include "rebraid/accel.h"
#include "rebraid/scene.h"
#include "viewer/camera.h"
#include "viewer/image_io.h"

namespace rebraid::viewer {

/// Parameters of the ambient-occlusion renderer.
struct AoSettings {
    /// Image size in pixels.
    int width = 640;
    int height = 360;
    /// Occlusion rays per primary hit; more = smoother, slower (linear).
    int samples_per_pixel = 8;
    /// Occlusion ray length, as a fraction of the scene's bounding-box diagonal. Longer rays
    /// darken more of the scene (large-scale shadowing), shorter ones only creases.
    float radius_fraction = 0.05f;
    /// Shading brightness where nothing is occluded is 1; fully occluded points keep this.
    float ambient_floor = 0.25f;
    /// Seed of the per-pixel sample streams: the same seed gives the same image on any
    /// thread count.
    std::uint64_t seed = 1;
    /// The scene's vertical, for the sky and the key light; glTF's is +Y.
    Vec3f world_up{0.0f, 1.0f, 0.0f};

    /// Throws rebraid::Error naming the first field out of range.
    void validate() const;
};

/// Called from worker threads with the number of image rows just finished; must be
/// thread-safe. Used for progress display.
using RowsDoneCallback = std::function<void(int row_count)>;

/// Renders `scene` through `accel` (built over that same scene) with ambient occlusion: one
/// primary ray per pixel centre; at a hit, `samples_per_pixel` cosine-distributed occlusion
/// rays around the geometric normal, times a per-instance tint and a soft key light; the sky
/// where the ray misses. Rows run in parallel (TBB); each pixel draws its samples from its
/// own seeded stream, so the image does not depend on the thread count. Display-ready
/// (sRGB) values in [0, 1].
Image render_ao(const Scene& scene, const Accel& accel, const Camera& camera,
                const AoSettings& settings, const RowsDoneCallback& on_rows_done = {});

}  // namespace rebraid::viewer
