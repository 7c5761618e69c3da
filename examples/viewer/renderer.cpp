#include "viewer/renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/error.h"
#include "rebraid/random.h"
#include "viewer/shading.h"

namespace rebraid::viewer {

namespace {

/// Sizes above this are almost certainly typos (and would need gigabytes).
constexpr int kMaxImageSide = 32768;

/// What the per-pixel shading needs besides the ray.
struct ShadingContext {
    const Scene& scene;
    const Accel& accel;
    const AoSettings& settings;
    float ao_radius;   ///< world units
    float ray_offset;  ///< world units, lifts occlusion rays off their surface
    Vec3f world_up;    ///< unit
    Vec3f key_light;   ///< unit direction towards the light
};

/// `column_of_row` is scratch space, reused across the pixels of a row to avoid allocations.
Vec3f shade_pixel(const ShadingContext& context, const Ray& primary, Random& random,
                  std::vector<int>& column_of_row) {
    const Hit hit = context.accel.intersect(primary);
    if (!hit.is_hit()) return sky_colour(primary.dir, context.world_up);

    Vec3f normal = world_geometric_normal(context.scene, hit.instance_id, hit.prim_id);
    // Shade the side the camera sees, whatever the winding.
    if (dot(normal, primary.dir) > 0.0f) normal = -normal;
    const Vec3f position = primary.org + primary.dir * hit.t;

    // N-rooks (Latin hypercube) samples: each of the n strata of both sample dimensions is
    // hit exactly once, which removes most of the noise of independent samples at low n.
    const int sample_count = context.settings.samples_per_pixel;
    column_of_row.resize(static_cast<std::size_t>(sample_count));
    std::iota(column_of_row.begin(), column_of_row.end(), 0);
    for (int i = sample_count - 1; i > 0; --i)  // Fisher-Yates with our own generator
        std::swap(column_of_row[i], column_of_row[random.next_below(i + 1)]);
    int unoccluded_count = 0;
    for (int sample = 0; sample < sample_count; ++sample) {
        const float u1 = (static_cast<float>(sample) + random.next_float01()) / sample_count;
        const float u2 =
            (static_cast<float>(column_of_row[sample]) + random.next_float01()) / sample_count;
        Ray occlusion_ray;
        occlusion_ray.org = position + normal * context.ray_offset;
        occlusion_ray.dir = sample_cosine_hemisphere(normal, u1, u2);
        occlusion_ray.tnear = 0.0f;
        occlusion_ray.tfar = context.ao_radius;
        if (!context.accel.occluded(occlusion_ray)) ++unoccluded_count;
    }
    const float visibility = static_cast<float>(unoccluded_count) /
                             static_cast<float>(context.settings.samples_per_pixel);
    const float ambient =
        context.settings.ambient_floor + (1.0f - context.settings.ambient_floor) * visibility;
    // A gentle key light so shapes read even where occlusion is uniform.
    const float key = 0.7f + 0.3f * std::max(0.0f, dot(normal, context.key_light));
    return instance_tint(hit.instance_id) * (ambient * key);
}

}  // namespace

void AoSettings::validate() const {
    if (width < 1 || width > kMaxImageSide)
        throw Error("AoSettings: width " + std::to_string(width) + " is outside [1, " +
                    std::to_string(kMaxImageSide) + "]");
    if (height < 1 || height > kMaxImageSide)
        throw Error("AoSettings: height " + std::to_string(height) + " is outside [1, " +
                    std::to_string(kMaxImageSide) + "]");
    if (samples_per_pixel < 1)
        throw Error("AoSettings: samples_per_pixel " + std::to_string(samples_per_pixel) +
                    " must be at least 1");
    if (!(radius_fraction > 0.0f) || !std::isfinite(radius_fraction))
        throw Error("AoSettings: radius_fraction " + std::to_string(radius_fraction) +
                    " must be positive");
    if (!(ambient_floor >= 0.0f && ambient_floor <= 1.0f))
        throw Error("AoSettings: ambient_floor " + std::to_string(ambient_floor) +
                    " is outside [0, 1]");
    if (!(length(world_up) > 0.0f)) throw Error("AoSettings: world_up is the zero vector");
}

Image render_ao(const Scene& scene, const Accel& accel, const Camera& camera,
                const AoSettings& settings, const RowsDoneCallback& on_rows_done) {
    settings.validate();
    const BBox3f bounds = scene.bounds();
    const float scene_size = bounds.is_empty() ? 1.0f : std::max(length(bounds.extent()), 1e-6f);
    const Vec3f world_up = normalize(settings.world_up);
    // The light comes from above, over the camera's right shoulder.
    const Vec3f key_light = normalize(world_up * 2.0f + camera.right - camera.forward * 0.5f);
    const ShadingContext context{.scene = scene,
                                 .accel = accel,
                                 .settings = settings,
                                 .ao_radius = settings.radius_fraction * scene_size,
                                 .ray_offset = 1e-4f * scene_size,
                                 .world_up = world_up,
                                 .key_light = key_light};

    Image image;
    image.width = settings.width;
    image.height = settings.height;
    image.rgb.assign(3 * static_cast<std::size_t>(image.width) * image.height, 0.0f);

    tbb::parallel_for(
        tbb::blocked_range<int>(0, image.height), [&](const tbb::blocked_range<int>& rows) {
            std::vector<int> column_of_row;
            for (int y = rows.begin(); y != rows.end(); ++y) {
                for (int x = 0; x < image.width; ++x) {
                    const std::size_t pixel_id = static_cast<std::size_t>(y) * image.width + x;
                    // One stream per pixel, keyed by seed and pixel: thread-count independent.
                    Random random(settings.seed * 0x9e3779b97f4a7c15ull + pixel_id);
                    const Ray primary =
                        camera.ray_through(static_cast<float>(x) + 0.5f,
                                           static_cast<float>(y) + 0.5f, image.width, image.height);
                    const Vec3f colour =
                        linear_to_srgb(shade_pixel(context, primary, random, column_of_row));
                    image.rgb[3 * pixel_id + 0] = colour.x;
                    image.rgb[3 * pixel_id + 1] = colour.y;
                    image.rgb[3 * pixel_id + 2] = colour.z;
                }
            }
            if (on_rows_done) on_rows_done(static_cast<int>(rows.size()));
        });
    return image;
}

}  // namespace rebraid::viewer
