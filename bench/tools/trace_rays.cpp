// trace_rays [OPTIONS] SCENE RAYS... ACCEL[,ACCEL...]: builds each structure over a glTF scene (or
// `default`), traces each ray file through it on one thread (one trace_all call per file and
// structure, in order) and prints what it found, one line per file and structure. A
// deterministic workload for instruction counts, free of the libraries the `rebraid` command
// links for images (which valgrind cannot run):
//   valgrind --tool=callgrind --toggle-collect='*trace_all*' ./build/bench/trace_rays SCENE
//       RAYS ACCEL
// With several ray files, --dump-after='*trace_all*' writes one profile per file, so one
// build (emulated slowly by valgrind) serves them all (bench/tools/count_instructions.py).
// ACCEL: a structure as `rebraid bench --accel` names one, variants included
// (`rebraid:budget-factor=16`). Embree's structures are traced as the benchmarks time them:
// rtcIntersect1 and rtcOccluded1 on rays converted to Embree's layout before the trace
// (glue::EmbreeRayBatch), so that their counts are Embree's queries without a wrapper.
// Options, before the scene:
//   --count-work    each line also gives the nodes, triangles and object entries per
//                   closest-hit query (TraversalCounters), from a second pass after each
//                   file's trace_all; callgrind would count that pass with the next file's
//                   trace_all, so leave the option out when counting instructions.
//   --closest-only  trace closest hits only (no occlusion query per ray).
//   --located       trace the closest hits of instanced structures (InstancedAccel) with their
//                   located query, as the Embree glue asks them (the hit triangle's place,
//                   corners and Möller terms kept too); other structures as without it.
//   --rounds N      also time N rounds per file, the structures taking turns within each round
//                   (so that a change in machine load hits them alike), and give each one's
//                   median Mrays/s and the median of its rounds' ratios to the first structure.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accel_factory.h"
#include "embree_glue/reference/embree_ray_batch.h"
#include "rebraid/rebraid.h"

namespace {

struct TraceSummary {
    std::size_t hits = 0;
    std::size_t occluded = 0;
    double t_sum = 0.0;
};

/// A structure as this tool traces it: the project's through Accel, Embree's on rays already
/// in its layout (glue::EmbreeRayBatch), as `rebraid bench` times them. Each keeps its answers
/// in its own form (Hit, or the batch's RTCRayHit), read only after the trace.
struct TracedAccel {
    const rebraid::Accel& accel;
    const rebraid::InstancedAccel* located;  // traced with its located query when not null
    std::optional<rebraid::glue::EmbreeRayBatch> embree_rays;
    std::vector<rebraid::Hit> hits;       // the project's structures
    std::vector<unsigned char> occluded;  // the project's structures
};

/// Every ray's closest hit, then (unless `closest_only`) every ray's occlusion, each answer
/// stored as the structure gives it (no conversion of Embree's hits is counted or timed, as
/// `rebraid bench` converts them after its timing); not inlined, so callgrind can count it
/// alone. Embree's batch traces each pass in one call, as `rebraid bench` traces a block.
[[gnu::noinline]] void trace_all(TracedAccel& traced, const std::vector<rebraid::Ray>& rays,
                                 bool closest_only) {
    if (traced.embree_rays) {
        rebraid::glue::EmbreeRayBatch& batch = *traced.embree_rays;
        batch.intersect(0, rays.size());
        if (!closest_only) batch.occlude(0, rays.size());
        return;
    }
    if (traced.located != nullptr) {
        for (std::size_t i = 0; i < rays.size(); ++i)
            traced.hits[i] = traced.located->intersect_located(rays[i], nullptr).hit;
    } else {
        for (std::size_t i = 0; i < rays.size(); ++i)
            traced.hits[i] = traced.accel.intersect(rays[i]);
    }
    if (closest_only) return;
    for (std::size_t i = 0; i < rays.size(); ++i)
        traced.occluded[i] = traced.accel.occluded(rays[i]) ? 1 : 0;
}

/// What the last trace_all of `traced` found over `count` rays.
TraceSummary summarize(const TracedAccel& traced, std::size_t count, bool closest_only) {
    TraceSummary summary;
    for (std::size_t i = 0; i < count; ++i) {
        const rebraid::Hit hit = traced.embree_rays ? traced.embree_rays->hit(i) : traced.hits[i];
        if (!hit.is_hit()) continue;
        ++summary.hits;
        summary.t_sum += hit.t;
    }
    if (!closest_only)
        for (std::size_t i = 0; i < count; ++i)
            summary.occluded +=
                traced.embree_rays ? traced.embree_rays->is_occluded(i) : traced.occluded[i] != 0;
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

double median(std::vector<double> values) {
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
}

std::vector<std::string> split_list(const std::string& list) {
    std::vector<std::string> names;
    for (std::size_t begin = 0;;) {
        const std::size_t comma = list.find(',', begin);
        names.push_back(list.substr(begin, comma - begin));
        if (comma == std::string::npos) return names;
        begin = comma + 1;
    }
}

}  // namespace

int main(int argc, char** argv) {
    bool counts_work = false, closest_only = false, located = false;
    int rounds = 0;
    int first = 1;
    for (; first < argc; ++first) {
        const std::string_view arg = argv[first];
        if (arg == "--count-work") {
            counts_work = true;
        } else if (arg == "--closest-only") {
            closest_only = true;
        } else if (arg == "--located") {
            located = true;
        } else if (arg == "--rounds" && first + 1 < argc) {
            rounds = std::max(0, std::atoi(argv[++first]));
        } else {
            break;
        }
    }
    if (argc - first < 3) {
        std::fprintf(stderr,
                     "usage: trace_rays [--count-work] [--closest-only] [--located] [--rounds N] "
                     "SCENE|default RAYS... ACCEL[,ACCEL...]\n");
        return 1;
    }
    try {
        const std::string scene_path = argv[first];
        const rebraid::Scene scene = scene_path == "default" ? rebraid::make_default_scene()
                                                             : rebraid::load_gltf_scene(scene_path);
        // Every ray file is read before the builds, so a bad one fails at once.
        std::vector<std::vector<rebraid::Ray>> ray_sets;
        for (int file = first + 1; file < argc - 1; ++file)
            ray_sets.push_back(rebraid::read_ray_file(argv[file]));
        const std::vector<std::string> names = split_list(argv[argc - 1]);
        std::vector<std::unique_ptr<rebraid::Accel>> accels;
        for (const std::string& name : names)
            accels.push_back(rebraid::cli::build_accel(name, scene));
        for (const std::vector<rebraid::Ray>& rays : ray_sets) {
            std::vector<TracedAccel> traced;
            for (const auto& accel : accels) {
                traced.push_back(
                    {*accel,
                     located ? dynamic_cast<const rebraid::InstancedAccel*>(accel.get()) : nullptr,
                     std::nullopt,
                     {},
                     {}});
                if (rebraid::glue::EmbreeRayBatch::serves(*accel)) {
                    traced.back().embree_rays.emplace(*accel, rays);
                } else {
                    traced.back().hits.resize(rays.size());
                    traced.back().occluded.resize(rays.size());
                }
            }
            // The untimed pass of each structure is also the timed rounds' warm-up.
            std::vector<TraceSummary> summaries;
            for (TracedAccel& t : traced) {
                trace_all(t, rays, closest_only);
                summaries.push_back(summarize(t, rays.size(), closest_only));
            }
            std::vector<std::vector<double>> mrays(accels.size());  // per structure and round
            for (int round = 0; round < rounds; ++round)
                for (std::size_t a = 0; a < accels.size(); ++a) {
                    const auto start = std::chrono::steady_clock::now();
                    trace_all(traced[a], rays, closest_only);
                    const std::chrono::duration<double> took =
                        std::chrono::steady_clock::now() - start;
                    mrays[a].push_back(double(rays.size()) / took.count() * 1e-6);
                }
            for (std::size_t a = 0; a < accels.size(); ++a) {
                const TraceSummary& summary = summaries[a];
                if (accels.size() > 1) std::printf("%s: ", names[a].c_str());
                std::printf("%zu rays, %zu hits, %zu occluded, t sum %.9g", rays.size(),
                            summary.hits, summary.occluded, summary.t_sum);
                if (rounds > 0) {
                    std::vector<double> ratios;
                    for (int round = 0; round < rounds; ++round)
                        ratios.push_back(mrays[a][round] / mrays[0][round]);
                    std::printf(", %.3f Mrays/s, %.3f of the first", median(mrays[a]),
                                median(ratios));
                }
                if (counts_work) {
                    const rebraid::TraversalCounters work = count_work(*accels[a], rays);
                    const double n = double(std::max<std::size_t>(rays.size(), 1));
                    std::printf(", per ray %.3f nodes %.3f triangles %.3f entries",
                                double(work.nodes_visited) / n, double(work.triangles_tested) / n,
                                double(work.object_entries) / n);
                }
                std::printf("\n");
            }
        }
    } catch (const std::exception& error) {
        std::fprintf(stderr, "trace_rays: %s\n", error.what());
        return 1;
    }
    return 0;
}
