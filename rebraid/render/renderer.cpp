#include "rebraid/render/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/render/colour.h"
#include "rebraid/render/shading.h"
#include "rebraid/render/surface_hit.h"

namespace rebraid::viewer {

namespace {

/// Sizes above this are almost certainly typos (and would need gigabytes).
constexpr int kMaxImageSide = 32768;
constexpr int kMaxBounces = 64;

/// Everything a pixel's shading reads; shared by all threads.
struct ShadingContext {
    const Scene& scene;
    const Accel& accel;
    const SurfaceMaterials& materials;
    const RenderSettings& settings;
    float ao_radius;   ///< world units
    float ray_offset;  ///< world units, lifts secondary rays off their surface
    Vec3f world_up;    ///< unit
    Vec3f key_light;   ///< ao: unit direction towards the key light
    Vec3f sun;         ///< path: unit direction towards the sun
};

/// Scratch reused across the pixels of a row to avoid allocations.
struct RowScratch {
    std::vector<int> column_of_row;
};

/// A ray leaving `surface` in `direction`, lifted off it against self-intersection.
Ray secondary_ray(const ShadingContext& context, const SurfaceHit& surface, Vec3f direction,
                  float tfar = std::numeric_limits<float>::infinity()) {
    Ray ray;
    ray.org = surface.position + surface.normal * context.ray_offset;
    ray.dir = direction;
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    return ray;
}

Vec3f shade_ao(const ShadingContext& context, const Ray& primary, Random& random,
               RowScratch& scratch) {
    const Hit hit = context.accel.intersect(primary);
    if (!hit.is_hit()) return sky_colour(primary.dir, context.world_up);
    const SurfaceHit surface = make_surface_hit(context.scene, primary, hit);
    if (surface.normal == Vec3f{}) return {};

    // N-rooks (Latin hypercube) samples: each of the n strata of both sample dimensions is
    // hit exactly once, which removes most of the noise of independent samples at low n.
    const int sample_count = context.settings.samples_per_pixel;
    std::vector<int>& column_of_row = scratch.column_of_row;
    column_of_row.resize(static_cast<std::size_t>(sample_count));
    std::iota(column_of_row.begin(), column_of_row.end(), 0);
    for (int i = sample_count - 1; i > 0; --i)  // Fisher-Yates with our own generator
        std::swap(column_of_row[i], column_of_row[random.next_below(i + 1)]);
    int unoccluded_count = 0;
    for (int sample = 0; sample < sample_count; ++sample) {
        const float u1 = (static_cast<float>(sample) + random.next_float01()) / sample_count;
        const float u2 =
            (static_cast<float>(column_of_row[sample]) + random.next_float01()) / sample_count;
        const Ray occlusion_ray = secondary_ray(
            context, surface, sample_cosine_hemisphere(surface.normal, u1, u2), context.ao_radius);
        if (!context.accel.occluded(occlusion_ray)) ++unoccluded_count;
    }
    const float visibility =
        static_cast<float>(unoccluded_count) / static_cast<float>(sample_count);
    const float ambient =
        context.settings.ambient_floor + (1.0f - context.settings.ambient_floor) * visibility;
    // A gentle key light so shapes read even where occlusion is uniform.
    const float key = 0.7f + 0.3f * std::max(0.0f, dot(surface.normal, context.key_light));
    return context.materials.base_colour(context.scene, surface) * (ambient * key);
}

/// One diffuse path: at each hit, the sun through a shadow ray (next-event estimation),
/// then a cosine-distributed bounce; the sky ends the path.
Vec3f trace_path(const ShadingContext& context, Ray ray, Random& random) {
    const RenderSettings& settings = context.settings;
    Vec3f radiance{}, throughput{1.0f, 1.0f, 1.0f};
    for (int bounce = 0;; ++bounce) {
        const Hit hit = context.accel.intersect(ray);
        if (!hit.is_hit()) {
            radiance = radiance +
                       throughput * sky_colour(ray.dir, context.world_up) * settings.sky_intensity;
            break;
        }
        const SurfaceHit surface = make_surface_hit(context.scene, ray, hit);
        if (surface.normal == Vec3f{}) break;
        // Lambertian: with cosine-distributed bounces, the throughput picks up the albedo.
        throughput = throughput * context.materials.base_colour(context.scene, surface);
        if (settings.sun_intensity > 0.0f) {
            const float cosine = dot(surface.normal, context.sun);
            if (cosine > 0.0f &&
                !context.accel.occluded(secondary_ray(context, surface, context.sun)))
                radiance = radiance + throughput * (settings.sun_intensity * cosine);
        }
        if (bounce == settings.max_bounces) break;
        const float u1 = random.next_float01(), u2 = random.next_float01();
        ray = secondary_ray(context, surface, sample_cosine_hemisphere(surface.normal, u1, u2));
    }
    return radiance;
}

Vec3f shade_normals(const ShadingContext& context, const Ray& primary) {
    const Hit hit = context.accel.intersect(primary);
    if (!hit.is_hit()) return srgb_to_linear(Vec3f{0.12f, 0.12f, 0.14f});
    const SurfaceHit surface = make_surface_hit(context.scene, primary, hit);
    return srgb_to_linear(surface.normal * 0.5f + Vec3f{0.5f, 0.5f, 0.5f});
}

Vec3f shade_pixel(const ShadingContext& context, const Camera& camera, int x, int y, Random& random,
                  RowScratch& scratch) {
    const RenderSettings& settings = context.settings;
    const float centre_x = static_cast<float>(x) + 0.5f, centre_y = static_cast<float>(y) + 0.5f;
    switch (settings.mode) {
        case ShadingMode::ao:
            return shade_ao(context,
                            camera.ray_through(centre_x, centre_y, settings.width, settings.height),
                            random, scratch);
        case ShadingMode::normals:
            return shade_normals(
                context, camera.ray_through(centre_x, centre_y, settings.width, settings.height));
        case ShadingMode::path: {
            Vec3f sum{};
            for (int sample = 0; sample < settings.samples_per_pixel; ++sample) {
                // Anti-aliasing: each path starts at its own point of the pixel.
                const float jitter_x = random.next_float01(), jitter_y = random.next_float01();
                const Ray primary = camera.ray_through(static_cast<float>(x) + jitter_x,
                                                       static_cast<float>(y) + jitter_y,
                                                       settings.width, settings.height);
                sum = sum + trace_path(context, primary, random);
            }
            return sum / static_cast<float>(settings.samples_per_pixel);
        }
    }
    return {};
}

/// Two unit vectors perpendicular to `up` and to each other.
std::pair<Vec3f, Vec3f> horizontal_axes(Vec3f up) {
    const Vec3f reference =
        std::fabs(up.z) < 0.9f ? Vec3f{0.0f, 0.0f, 1.0f} : Vec3f{1.0f, 0.0f, 0.0f};
    const Vec3f a = normalize(cross(up, reference));
    return {a, cross(a, up)};
}

}  // namespace

std::string_view shading_mode_name(ShadingMode mode) {
    switch (mode) {
        case ShadingMode::ao:
            return "ao";
        case ShadingMode::path:
            return "path";
        case ShadingMode::normals:
            return "normals";
    }
    return "unknown";
}

void RenderSettings::validate() const {
    auto fail = [](const std::string& what) { throw Error("RenderSettings: " + what); };
    if (width < 1 || width > kMaxImageSide)
        fail("width " + std::to_string(width) + " is outside [1, " + std::to_string(kMaxImageSide) +
             "]");
    if (height < 1 || height > kMaxImageSide)
        fail("height " + std::to_string(height) + " is outside [1, " +
             std::to_string(kMaxImageSide) + "]");
    if (samples_per_pixel < 1)
        fail("samples_per_pixel " + std::to_string(samples_per_pixel) + " must be at least 1");
    if (max_bounces < 0 || max_bounces > kMaxBounces)
        fail("max_bounces " + std::to_string(max_bounces) + " is outside [0, " +
             std::to_string(kMaxBounces) + "]");
    if (!(ao_radius_fraction > 0.0f) || !std::isfinite(ao_radius_fraction))
        fail("ao_radius_fraction " + std::to_string(ao_radius_fraction) + " must be positive");
    if (!(ambient_floor >= 0.0f && ambient_floor <= 1.0f))
        fail("ambient_floor " + std::to_string(ambient_floor) + " is outside [0, 1]");
    if (!(sky_intensity >= 0.0f) || !std::isfinite(sky_intensity))
        fail("sky_intensity " + std::to_string(sky_intensity) + " must be >= 0");
    if (!(sun_intensity >= 0.0f) || !std::isfinite(sun_intensity))
        fail("sun_intensity " + std::to_string(sun_intensity) + " must be >= 0");
    if (!(length(world_up) > 0.0f) || !is_finite(world_up)) fail("world_up is not a direction");
}

RenderResult render_image(const Scene& scene, const Accel& accel, const Camera& camera,
                          const SurfaceMaterials& materials, const RenderSettings& settings,
                          const RenderControl& control) {
    settings.validate();
    const BBox3f bounds = scene.bounds();
    const float scene_size = bounds.is_empty() ? 1.0f : std::max(length(bounds.extent()), 1e-6f);
    const Vec3f world_up = normalize(settings.world_up);
    const auto [east, north] = horizontal_axes(world_up);
    const ShadingContext context{
        .scene = scene,
        .accel = accel,
        .materials = materials,
        .settings = settings,
        .ao_radius = settings.ao_radius_fraction * scene_size,
        .ray_offset = 1e-4f * scene_size,
        .world_up = world_up,
        // Over the camera's right shoulder, from above.
        .key_light = normalize(world_up * 2.0f + camera.right - camera.forward * 0.5f),
        // Fixed in the world (about 55 degrees high), so animation frames share the light.
        .sun = normalize(world_up * 1.4f + east * 0.8f + north * 0.5f),
    };

    RenderResult result;
    result.image = Image::filled(settings.width, settings.height);
    std::vector<char> row_is_done;
    result.rows_done = for_each_row(
        settings.height, control,
        [&](int y) {
            RowScratch scratch;
            for (int x = 0; x < settings.width; ++x) {
                const std::size_t pixel_id = static_cast<std::size_t>(y) * settings.width + x;
                // One stream per pixel, keyed by seed and pixel: thread-count independent.
                Random random(settings.seed * 0x9e3779b97f4a7c15ull + pixel_id);
                result.image.set_pixel(x, y, shade_pixel(context, camera, x, y, random, scratch));
            }
        },
        row_is_done);
    return result;
}

}  // namespace rebraid::viewer
