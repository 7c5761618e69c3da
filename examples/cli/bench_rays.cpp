#include "bench_rays.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "rebraid/core/error.h"
#include "rebraid/core/random.h"
#include "rebraid/render/camera.h"
#include "rebraid/render/shading.h"

namespace rebraid::cli {

BenchRays make_bench_rays(const Scene& scene, const Accel& reference,
                          const BenchRaySettings& settings) {
    if (settings.ray_count == 0) throw Error("make_bench_rays: ray_count must be at least 1");
    if (!(settings.aspect > 0.0f) || !std::isfinite(settings.aspect))
        throw Error("make_bench_rays: aspect " + std::to_string(settings.aspect) +
                    " must be positive");
    BenchRays rays;
    const std::size_t count = settings.ray_count;
    // The smallest image of the requested aspect holding `count` pixels, filled row by row.
    // (The tolerance keeps 640 x 360 = 230,400 at 16:9 from rounding up to 641 columns.)
    const double exact_width = std::sqrt(static_cast<double>(count) * settings.aspect);
    rays.image_width = std::max(1, static_cast<int>(std::ceil(exact_width - 1e-3)));
    rays.image_height = static_cast<int>((count + rays.image_width - 1) / rays.image_width);
    const viewer::Camera camera = viewer::frame_scene(
        scene, static_cast<float>(rays.image_width) / static_cast<float>(rays.image_height));

    rays.primary.resize(count);
    std::vector<Hit> hits(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i != range.end(); ++i) {
                              const auto x = static_cast<float>(i % rays.image_width);
                              const auto y = static_cast<float>(i / rays.image_width);
                              rays.primary[i] = camera.ray_through(
                                  x + 0.5f, y + 0.5f, rays.image_width, rays.image_height);
                              hits[i] = reference.intersect(rays.primary[i]);
                          }
                      });

    std::vector<std::size_t> hitting;  // primary rays that hit, in ray order
    for (std::size_t i = 0; i < count; ++i)
        if (hits[i].is_hit()) hitting.push_back(i);
    rays.primary_hit_count = hitting.size();
    if (hitting.empty()) return rays;

    // Lift the origins off their surface by a small fraction of the scene, as the renderer
    // does, so a bounce does not hit its own triangle.
    const BBox3f bounds = scene.bounds();
    const float offset = 1e-4f * std::max(length(bounds.extent()), 1e-6f);
    rays.diffuse.resize(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i != range.end(); ++i) {
                              const std::size_t source = hitting[i % hitting.size()];
                              const Ray& primary = rays.primary[source];
                              const Hit& hit = hits[source];
                              Vec3f normal = viewer::world_geometric_normal(scene, hit.instance_id,
                                                                            hit.prim_id);
                              // A triangle too thin for a normal: bounce back towards the camera
                              // instead.
                              if (!(dot(normal, normal) > 0.0f)) normal = -normalize(primary.dir);
                              if (dot(normal, primary.dir) > 0.0f) normal = -normal;
                              // One stream per ray, keyed by seed and index: thread-count
                              // independent.
                              Random random(settings.seed * 0x9e3779b97f4a7c15ull + i);
                              const float u1 = random.next_float01();
                              const float u2 = random.next_float01();
                              Ray& bounce = rays.diffuse[i];
                              bounce.org = primary.org + primary.dir * hit.t + normal * offset;
                              bounce.dir = viewer::sample_cosine_hemisphere(normal, u1, u2);
                          }
                      });
    return rays;
}

}  // namespace rebraid::cli
