#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"
#include "rebraid/render/camera.h"
#include "rebraid/render/image_io.h"
#include "rebraid/render/render_control.h"
#include "rebraid/render/surface_materials.h"

namespace rebraid::viewer {

/// What a pixel shows.
enum class ShadingMode {
    ao,       ///< ambient occlusion times the base colour, under a soft key light
    path,     ///< diffuse path tracing under the sky and a sun
    normals,  ///< the world-space geometric normal as a colour (0.5 + 0.5 n)
};

/// The name `--mode` uses ("ao", "path", "normals").
std::string_view shading_mode_name(ShadingMode mode);

/// Parameters of the image renderer. Defaults give a quick preview.
struct RenderSettings {
    /// Image size in pixels.
    int width = 640;
    int height = 360;
    ShadingMode mode = ShadingMode::ao;
    /// ao: occlusion rays per pixel; path: paths per pixel (each from a jittered point of
    /// the pixel); normals: unused. More = smoother, slower (linear).
    int samples_per_pixel = 8;
    /// path: diffuse bounces after the first hit (the paper measures up to 8).
    int max_bounces = 8;
    /// ao: occlusion ray length, as a fraction of the scene's bounding-box diagonal. Longer
    /// rays darken more of the scene (large-scale shadowing), shorter ones only creases.
    float ao_radius_fraction = 0.05f;
    /// ao: brightness kept by fully occluded points (unoccluded ones get 1).
    float ambient_floor = 0.25f;
    /// path: radiance scale of the sky, which lights the scene.
    float sky_intensity = 0.7f;
    /// path: irradiance of a sun high in the sky, relative to a white sky; 0 = sky only.
    float sun_intensity = 0.9f;
    /// Seed of the per-pixel sample streams: the same seed gives the same image on any
    /// thread count.
    std::uint64_t seed = 1;
    /// The scene's vertical, for the sky and the lights; glTF's is +Y.
    Vec3f world_up{0.0f, 1.0f, 0.0f};

    /// Throws rebraid::Error naming the first field out of range.
    void validate() const;
};

/// A rendered image; rows the render did not reach (after a stop request) are black.
struct RenderResult {
    Image image;
    int rows_done = 0;
    bool is_complete() const { return rows_done == image.height; }
};

/// Renders `scene` through `accel` (built over that same scene), one row per task (TBB).
/// Shading uses only data every structure agrees on (make_surface_hit()), and each pixel
/// draws its samples from its own stream seeded by (seed, pixel), so the image is the same
/// for any thread count and any structure that finds the same hits. Linear values.
RenderResult render_image(const Scene& scene, const Accel& accel, const Camera& camera,
                          const SurfaceMaterials& materials, const RenderSettings& settings,
                          const RenderControl& control = {});

}  // namespace rebraid::viewer
