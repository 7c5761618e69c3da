// trace_rays SCENE RAYS ACCEL: builds one structure over a glTF scene (or `default`), traces
// a ray file through it on one thread and prints what it found. A deterministic workload for
// instruction counts, free of the libraries the `rebraid` command links for images (which
// valgrind cannot run):
//   valgrind --tool=callgrind --toggle-collect='*trace_all*' ./build/bench/trace_rays SCENE
//       RAYS ACCEL
// ACCEL: flat, twolevel, rebraid, embree-flat or embree-instanced.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/rebraid.h"

namespace {

std::unique_ptr<rebraid::Accel> build(const std::string& name, const rebraid::Scene& scene) {
    if (name == "flat") return std::make_unique<rebraid::FlatAccel>(scene);
    if (name == "twolevel")
        return std::make_unique<rebraid::InstancedAccel>(rebraid::build_two_level_accel(scene));
    if (name == "rebraid")
        return std::make_unique<rebraid::InstancedAccel>(rebraid::build_rebraid_accel(scene));
    if (name == "embree-flat") return std::make_unique<rebraid::glue::EmbreeFlatAccel>(scene);
    if (name == "embree-instanced")
        return std::make_unique<rebraid::glue::EmbreeInstancedAccel>(scene);
    throw rebraid::Error("unknown structure '" + name + "'");
}

struct TraceSummary {
    std::size_t hits = 0;
    std::size_t occluded = 0;
    double t_sum = 0.0;
};

/// Every ray's closest hit and occlusion; not inlined, so callgrind can count it alone.
[[gnu::noinline]] TraceSummary trace_all(const rebraid::Accel& accel,
                                         const std::vector<rebraid::Ray>& rays) {
    TraceSummary summary;
    for (const rebraid::Ray& ray : rays) {
        const rebraid::Hit hit = accel.intersect(ray);
        if (hit.is_hit()) {
            ++summary.hits;
            summary.t_sum += hit.t;
        }
        summary.occluded += accel.occluded(ray);
    }
    return summary;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: trace_rays SCENE|default RAYS ACCEL\n");
        return 1;
    }
    try {
        const std::string scene_path = argv[1];
        const rebraid::Scene scene = scene_path == "default" ? rebraid::make_default_scene()
                                                             : rebraid::load_gltf_scene(scene_path);
        const std::vector<rebraid::Ray> rays = rebraid::read_ray_file(argv[2]);
        const std::unique_ptr<rebraid::Accel> accel = build(argv[3], scene);
        const TraceSummary summary = trace_all(*accel, rays);
        std::printf("%zu rays, %zu hits, %zu occluded, t sum %.9g\n", rays.size(), summary.hits,
                    summary.occluded, summary.t_sum);
    } catch (const std::exception& error) {
        std::fprintf(stderr, "trace_rays: %s\n", error.what());
        return 1;
    }
    return 0;
}
