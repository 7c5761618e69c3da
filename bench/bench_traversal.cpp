// Single-ray traversal speed (Mrays/s) of the project's structures against Embree's, on the
// same rays: primary rays of a camera framing each scene, and incoherent random rays
// (rebraid/generators/random_rays.h), for closest hits and occlusion. Scenes: the default scene and
// every .glb of the scene folder.
//
//   bench_traversal [--scene-dir DIR] [--rays N] [--threads N] [--rounds N]
//                   [--benchmark_filter=REGEX]
//
// Two families of benchmarks:
// - KIND/SCENE/ACCEL (e.g. `random/cg57_cruiser/flat`): one structure, Google Benchmark's
//   timing; also reports hit%, and nodes/ray and tris/ray for the project's structures.
// - compare/KIND/SCENE: all four structures traced in turn, --rounds times; each gets its
//   best round (rays / time) and the ratios flat/embree-flat and twolevel/embree-instanced.
//   Alternating the structures and keeping the best round makes the ratios robust on a busy
//   machine: this is the family bench/RESULTS.md quotes.
// --scene-dir: folder of .glb scenes (default ../shared/scenes, as seen from the repo root);
// --rays: rays per kind and scene (default 200000; primary rays round it to a square image);
// --threads: tracing threads (default 1: single-ray speed, timed by the thread's CPU time;
// more: wall-clock time); --rounds: rounds of the compare benchmarks (default 5);
// --leaf-size, --intersection-cost, --collapse greedy|optimal, --fill-nodes 0|1 (with greedy),
// --max-children N, --pre-arranged-leaves 0|1: BuildSettings of the flat and object BVHs (default:
// the builder's defaults), to measure how the tree shape changes traversal speed. Structures are
// built once per scene, outside the timed loops; Embree's structures are traced on rays
// already in Embree's layout (glue::EmbreeRayBatch), converted outside them too.
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_ray_batch.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid {
namespace {

/// Command-line settings besides Google Benchmark's own.
struct BenchSettings {
    std::string scene_dir = "../shared/scenes";
    std::size_t ray_count = 200000;
    int thread_count = 1;
    int round_count = 5;
    std::uint64_t seed = 7;
    /// Object and flat BVH build settings (the builder's defaults unless overridden).
    BuildSettings build;
};

/// Pinhole camera rays of a `side` x `side` image (side = sqrt(ray_count)) looking at the
/// scene's bounding sphere from above and to the side (azimuth 35 degrees, elevation 30
/// degrees, 40 degree field of view), placed so the whole sphere is in view: coherent rays,
/// as for a rendered frame.
std::vector<Ray> make_primary_rays(const BBox3f& bounds, std::size_t ray_count) {
    const int side = std::max(1, int(std::lround(std::sqrt(double(ray_count)))));
    const Vec3f center = bounds.center();
    const float radius = std::max(0.5f * length(bounds.extent()), 1e-6f);
    const float half_fov = 20.0f * std::numbers::pi_v<float> / 180.0f;
    const float azimuth = 35.0f * std::numbers::pi_v<float> / 180.0f;
    const float elevation = 30.0f * std::numbers::pi_v<float> / 180.0f;
    const Vec3f to_eye{std::cos(elevation) * std::sin(azimuth), std::sin(elevation),
                       std::cos(elevation) * std::cos(azimuth)};
    const Vec3f eye = center + to_eye * (radius / std::sin(half_fov));
    const Vec3f forward = -to_eye;
    const Vec3f right = normalize(cross(forward, Vec3f{0.0f, 1.0f, 0.0f}));
    const Vec3f up = cross(right, forward);
    const float tan_half = std::tan(half_fov);
    std::vector<Ray> rays;
    rays.reserve(std::size_t(side) * side);
    for (int y = 0; y < side; ++y) {
        for (int x = 0; x < side; ++x) {
            const float sx = (2.0f * (x + 0.5f) / side - 1.0f) * tan_half;
            const float sy = (1.0f - 2.0f * (y + 0.5f) / side) * tan_half;
            Ray ray;
            ray.org = eye;
            ray.dir = normalize(forward + right * sx + up * sy);
            rays.push_back(ray);
        }
    }
    return rays;
}

/// A scene with its rays and structures, built when its first benchmark runs.
struct SceneFixture {
    std::string name;
    Scene scene;
    std::vector<Ray> primary_rays;
    std::vector<Ray> random_rays;
    std::vector<std::pair<std::string, std::unique_ptr<Accel>>> accels;

    const Accel& accel(const std::string& accel_name) const {
        for (const auto& [name_of, accel] : accels)
            if (name_of == accel_name) return *accel;
        throw Error("bench_traversal: no structure '" + accel_name + "'");
    }
};

using SceneLoader = std::function<Scene()>;

/// The command-line settings, set once in main() before any benchmark runs.
BenchSettings& settings() {
    static BenchSettings instance;
    return instance;
}

/// Only one scene's structures are alive at a time: benchmarks run in registration order, so
/// a scene is built once and released when the next scene's first benchmark runs.
const SceneFixture& fixture_for(const std::string& name, const SceneLoader& load) {
    static std::unique_ptr<SceneFixture> current;
    if (current && current->name == name) return *current;
    current.reset();
    auto fixture = std::make_unique<SceneFixture>();
    fixture->name = name;
    fixture->scene = load();
    const BBox3f bounds = fixture->scene.bounds();
    fixture->primary_rays = make_primary_rays(bounds, settings().ray_count);
    fixture->random_rays = generate_random_rays(bounds, settings().ray_count, settings().seed);
    const Scene& scene = fixture->scene;
    fixture->accels.emplace_back("flat", std::make_unique<FlatAccel>(scene, settings().build));
    fixture->accels.emplace_back("embree-flat", std::make_unique<glue::EmbreeFlatAccel>(scene));
    fixture->accels.emplace_back("twolevel", std::make_unique<InstancedAccel>(build_two_level_accel(
                                                 scene, own_object_bvh_builder(settings().build))));
    fixture->accels.emplace_back("embree-instanced",
                                 std::make_unique<glue::EmbreeInstancedAccel>(scene));
    // Structure sizes next to the timings, so a speed change can be told from a tree change.
    for (const auto& [accel_name, accel] : fixture->accels) {
        const AccelStats stats = accel->stats();
        std::cerr << "# " << name << "/" << accel_name << ": triangles " << stats.triangles
                  << ", nodes " << stats.nodes.value_or(0) << ", leaves "
                  << stats.leaves.value_or(0) << ", sah " << stats.sah.value_or(0.0)
                  << ", memory MB " << double(stats.memory_bytes.value_or(0)) * 1e-6
                  << ", build ms " << stats.build_ms << "\n";
    }
    current = std::move(fixture);
    return *current;
}

enum class Query { intersect, occluded };

/// What one benchmark traces: the ray set and the query.
struct Kind {
    const char* label;
    Query query;
    bool is_primary;
};
constexpr Kind kKinds[] = {{"primary", Query::intersect, true},
                           {"random", Query::intersect, false},
                           {"random_occluded", Query::occluded, false}};
constexpr const char* kAccelNames[] = {"flat", "embree-flat", "twolevel", "embree-instanced"};

const std::vector<Ray>& rays_of(const SceneFixture& fixture, const Kind& kind) {
    return kind.is_primary ? fixture.primary_rays : fixture.random_rays;
}

/// Seconds of the calling thread's CPU time (one tracing thread) or of wall-clock time.
double now_seconds() {
    if (settings().thread_count == 1) {
        timespec time;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &time);
        return double(time.tv_sec) + 1e-9 * double(time.tv_nsec);
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

/// A structure and the rays it traces: the project's through Accel, Embree's from rays already
/// in its layout (glue::EmbreeRayBatch, made before the timing), as `rebraid bench` times them.
struct TracedRays {
    TracedRays(const Accel& accel, const std::vector<Ray>& rays) : accel(accel), rays(rays) {
        if (glue::EmbreeRayBatch::serves(accel)) embree_rays.emplace(accel, rays);
    }
    const Accel& accel;
    const std::vector<Ray>& rays;
    std::optional<glue::EmbreeRayBatch> embree_rays;
};

/// Traces every ray once, on the calling thread or on `settings().thread_count` threads.
void trace_once(TracedRays& traced, Query query, std::vector<float>& sink) {
    const auto trace_range = [&](std::size_t begin, std::size_t end) {
        if (traced.embree_rays) {
            glue::EmbreeRayBatch& batch = *traced.embree_rays;
            if (query == Query::intersect) {
                batch.intersect(begin, end);
                for (std::size_t i = begin; i != end; ++i) sink[i] = batch.hit(i).t;
            } else {
                batch.occlude(begin, end);
                for (std::size_t i = begin; i != end; ++i) sink[i] = float(batch.is_occluded(i));
            }
            return;
        }
        for (std::size_t i = begin; i != end; ++i)
            sink[i] = query == Query::intersect ? traced.accel.intersect(traced.rays[i]).t
                                                : float(traced.accel.occluded(traced.rays[i]));
    };
    if (settings().thread_count == 1) {
        trace_range(0, traced.rays.size());
    } else {
        tbb::task_arena arena(settings().thread_count);
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, traced.rays.size(), 1024),
                              [&](const tbb::blocked_range<std::size_t>& range) {
                                  trace_range(range.begin(), range.end());
                              });
        });
    }
    benchmark::DoNotOptimize(sink.data());
    benchmark::ClobberMemory();
}

/// KIND/SCENE/ACCEL: traces every ray once per iteration.
void trace_rays(benchmark::State& state, const Accel& accel, const std::vector<Ray>& rays,
                Query query) {
    std::vector<float> sink(rays.size());
    TracedRays traced(accel, rays);
    for (auto _ : state) trace_once(traced, query, sink);
    state.counters["Mrays/s"] = benchmark::Counter(
        double(rays.size()) * double(state.iterations()) * 1e-6, benchmark::Counter::kIsRate);
    // Work per ray for the project's structures (Embree does not report it), outside timing.
    TraversalCounters counters;
    std::size_t hits = 0;
    for (const Ray& ray : rays) hits += accel.intersect_counted(ray, &counters).is_hit();
    state.counters["hit%"] = 100.0 * double(hits) / double(std::max<std::size_t>(rays.size(), 1));
    if (counters.nodes_visited > 0) {
        state.counters["nodes/ray"] = double(counters.nodes_visited) / double(rays.size());
        state.counters["tris/ray"] = double(counters.triangles_tested) / double(rays.size());
    }
}

/// compare/KIND/SCENE: one iteration is a round tracing all rays with every structure in
/// turn; each structure's best round gives its Mrays/s.
void compare_accels(benchmark::State& state, const SceneFixture& fixture, const Kind& kind) {
    const std::vector<Ray>& rays = rays_of(fixture, kind);
    std::vector<float> sink(rays.size());
    std::vector<double> best(std::size(kAccelNames), 1e30);
    std::vector<TracedRays> traced;
    traced.reserve(std::size(kAccelNames));
    for (const char* name : kAccelNames) traced.emplace_back(fixture.accel(name), rays);
    for (auto _ : state) {
        for (std::size_t a = 0; a < std::size(kAccelNames); ++a) {
            const double start = now_seconds();
            trace_once(traced[a], kind.query, sink);
            best[a] = std::min(best[a], now_seconds() - start);
        }
    }
    std::vector<double> mrays(best.size());
    for (std::size_t a = 0; a < best.size(); ++a) {
        mrays[a] = double(rays.size()) * 1e-6 / std::max(best[a], 1e-12);
        state.counters[kAccelNames[a]] = mrays[a];
    }
    state.counters["flat/embree"] = mrays[0] / mrays[1];
    state.counters["twolevel/embree"] = mrays[2] / mrays[3];
}

void register_scene(const std::string& name, const SceneLoader& load) {
    for (const Kind& kind : kKinds) {
        for (const char* accel_name : kAccelNames) {
            const std::string bench_name = std::string(kind.label) + "/" + name + "/" + accel_name;
            benchmark::internal::Benchmark* bench = benchmark::RegisterBenchmark(
                bench_name.c_str(),
                [name, load, kind, accel_name = std::string(accel_name)](benchmark::State& state) {
                    const SceneFixture& fixture = fixture_for(name, load);
                    trace_rays(state, fixture.accel(accel_name), rays_of(fixture, kind),
                               kind.query);
                });
            bench->Unit(benchmark::kMillisecond);
            // One thread traces on the calling thread: its CPU time is the measure least
            // disturbed by other processes. Several threads: wall-clock time.
            if (settings().thread_count > 1) bench->UseRealTime();
        }
    }
    for (const Kind& kind : kKinds) {
        const std::string bench_name = std::string("compare/") + kind.label + "/" + name;
        benchmark::RegisterBenchmark(bench_name.c_str(),
                                     [name, load, kind](benchmark::State& state) {
                                         compare_accels(state, fixture_for(name, load), kind);
                                     })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(settings().round_count)
            ->UseRealTime();
    }
}

/// Removes `--NAME VALUE` or `--NAME=VALUE` from argv and returns VALUE ("" when absent).
std::string take_flag(int& argc, char** argv, const std::string& flag) {
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        std::string value;
        int used = 0;
        if (arg == flag && i + 1 < argc) {
            value = argv[i + 1];
            used = 2;
        } else if (arg.rfind(flag + "=", 0) == 0) {
            value = arg.substr(flag.size() + 1);
            used = 1;
        }
        if (used == 0) continue;
        for (int j = i; j + used < argc; ++j) argv[j] = argv[j + used];
        argc -= used;
        return value;
    }
    return "";
}

}  // namespace
}  // namespace rebraid

namespace rebraid {
namespace {

/// Parses the flags besides Google Benchmark's, registers every scene's benchmarks and runs
/// them. Throws for a malformed flag value.
int run(int argc, char** argv) {
    BenchSettings& bench = settings();
    if (std::string v = take_flag(argc, argv, "--scene-dir"); !v.empty()) bench.scene_dir = v;
    if (std::string v = take_flag(argc, argv, "--rays"); !v.empty())
        bench.ray_count = std::stoul(v);
    if (std::string v = take_flag(argc, argv, "--threads"); !v.empty())
        bench.thread_count = std::max(1, std::stoi(v));
    if (std::string v = take_flag(argc, argv, "--rounds"); !v.empty())
        bench.round_count = std::max(1, std::stoi(v));
    if (std::string v = take_flag(argc, argv, "--leaf-size"); !v.empty())
        bench.build.max_leaf_size = std::uint32_t(std::stoul(v));
    if (std::string v = take_flag(argc, argv, "--intersection-cost"); !v.empty())
        bench.build.intersection_cost = std::stof(v);
    if (std::string v = take_flag(argc, argv, "--collapse"); !v.empty()) {
        if (v != "greedy" && v != "optimal")
            throw std::invalid_argument("--collapse takes greedy or optimal, not " + v);
        bench.build.collapse = v == "greedy" ? NodeCollapse::greedy : NodeCollapse::optimal;
    }
    if (std::string v = take_flag(argc, argv, "--fill-nodes"); !v.empty()) {
        bench.build.fill_nodes = v != "0";
        if (bench.build.fill_nodes) bench.build.collapse = NodeCollapse::greedy;  // needs it
    }
    if (std::string v = take_flag(argc, argv, "--max-children"); !v.empty())
        bench.build.max_children = std::uint32_t(std::stoul(v));
    if (std::string v = take_flag(argc, argv, "--pre-arranged-leaves"); !v.empty())
        bench.build.pre_arranged_leaves = v != "0";
    bench.build.validate();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::AddCustomContext("scene_dir", bench.scene_dir);
    benchmark::AddCustomContext("rays", std::to_string(bench.ray_count));
    benchmark::AddCustomContext("threads", std::to_string(bench.thread_count));
    benchmark::AddCustomContext("rounds", std::to_string(bench.round_count));
    benchmark::AddCustomContext("leaf_size", std::to_string(bench.build.max_leaf_size));
    benchmark::AddCustomContext("intersection_cost", std::to_string(bench.build.intersection_cost));
    benchmark::AddCustomContext("fill_nodes", bench.build.fill_nodes ? "1" : "0");
    benchmark::AddCustomContext(
        "collapse", bench.build.collapse == NodeCollapse::greedy ? "greedy" : "optimal");
    benchmark::AddCustomContext("max_children", std::to_string(bench.build.max_children));
    benchmark::AddCustomContext("pre_arranged_leaves", bench.build.pre_arranged_leaves ? "1" : "0");

    register_scene("default", [] { return make_default_scene(); });
    std::vector<std::filesystem::path> files;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(bench.scene_dir, error))
        if (entry.path().extension() == ".glb") files.push_back(entry.path());
    if (error) std::cerr << "bench_traversal: cannot list " << bench.scene_dir << "\n";
    std::sort(files.begin(), files.end());
    for (const auto& path : files)
        register_scene(path.stem().string(), [path] { return load_gltf_scene(path.string()); });

    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}

}  // namespace
}  // namespace rebraid

int main(int argc, char** argv) {
    try {
        return rebraid::run(argc, argv);
    } catch (const std::exception& error) {
        std::cerr << "bench_traversal: " << error.what() << "\n";
        return 1;
    }
}
