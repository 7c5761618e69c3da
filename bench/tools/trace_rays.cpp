// trace_rays SCENE RAYS... ACCEL: builds one structure over a glTF scene (or `default`),
// traces each ray file through it on one thread (one trace_all call per file, in order) and
// prints what it found, one line per file. A deterministic workload for instruction counts,
// free of the libraries the `rebraid` command links for images (which valgrind cannot run):
//   valgrind --tool=callgrind --toggle-collect='*trace_all*' ./build/bench/trace_rays SCENE
//       RAYS ACCEL
// With several ray files, --dump-after='*trace_all*' writes one profile per file, so one
// build (emulated slowly by valgrind) serves them all (bench/tools/count_instructions.py).
// ACCEL: a structure as `rebraid bench --accel` names one, variants included
// (`rebraid:budget-factor=16`). With --count-work first, each line also gives the nodes,
// triangles and object entries per closest-hit query (TraversalCounters), from a second pass
// after each file's trace_all; callgrind would count that pass with the next file's
// trace_all, so leave the option out when counting instructions.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "accel_factory.h"
#include "rebraid/rebraid.h"

namespace {

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

/// Work per closest-hit query over `rays` (the structure's own counters; zero for structures
/// that keep none, such as Embree's).
rebraid::TraversalCounters count_work(const rebraid::Accel& accel,
                                      const std::vector<rebraid::Ray>& rays) {
    rebraid::TraversalCounters counters;
    for (const rebraid::Ray& ray : rays) accel.intersect_counted(ray, &counters);
    return counters;
}

}  // namespace

int main(int argc, char** argv) {
    const bool counts_work = argc > 1 && std::string_view(argv[1]) == "--count-work";
    if (counts_work) {
        --argc;
        ++argv;
    }
    if (argc < 4) {
        std::fprintf(stderr, "usage: trace_rays [--count-work] SCENE|default RAYS... ACCEL\n");
        return 1;
    }
    try {
        const std::string scene_path = argv[1];
        const rebraid::Scene scene = scene_path == "default" ? rebraid::make_default_scene()
                                                             : rebraid::load_gltf_scene(scene_path);
        // Every ray file is read before the build, so a bad one fails at once.
        std::vector<std::vector<rebraid::Ray>> ray_sets;
        for (int file = 2; file < argc - 1; ++file)
            ray_sets.push_back(rebraid::read_ray_file(argv[file]));
        const std::unique_ptr<rebraid::Accel> accel = rebraid::cli::build_accel(argv[argc - 1], scene);
        for (const std::vector<rebraid::Ray>& rays : ray_sets) {
            const TraceSummary summary = trace_all(*accel, rays);
            std::printf("%zu rays, %zu hits, %zu occluded, t sum %.9g", rays.size(), summary.hits,
                        summary.occluded, summary.t_sum);
            if (counts_work) {
                const rebraid::TraversalCounters work = count_work(*accel, rays);
                const double n = double(std::max<std::size_t>(rays.size(), 1));
                std::printf(", per ray %.3f nodes %.3f triangles %.3f entries",
                            double(work.nodes_visited) / n, double(work.triangles_tested) / n,
                            double(work.object_entries) / n);
            }
            std::printf("\n");
        }
    } catch (const std::exception& error) {
        std::fprintf(stderr, "trace_rays: %s\n", error.what());
        return 1;
    }
    return 0;
}
