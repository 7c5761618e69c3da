// Build-speed micro-benchmark: the project's own binned-SAH wide-BVH builder against Embree's
// own scene build (rtcCommitScene, medium quality) on the same world-space triangles, at 1 and
// 2 threads. Reports Mprims/s (and, for the own builder, the tree's SAH). Also the top-level
// builds alone (object BVHs built once beforehand): the plain two-level top, the re-braided
// top under the paper's rule and under the SAH-aware rule (the target "top build <= 2x
// twolevel"), reporting the top's items and the time per item.
//
// Usage: bench_build [--scene-dir=DIR] [--top-scene=FILE ...] [Google Benchmark flags, e.g.
//        --benchmark_filter=Own --benchmark_repetitions=3]
// DIR holds the shared .glb scenes; without the flag, $REBRAID_SHARED_SCENES, then
// <repo>/../shared/scenes (from this file's path), then ../shared/scenes. Each --top-scene
// adds a scene file (e.g. a generated one) to the top-level benchmarks, which otherwise run
// on the default scene and cg57_cruiser.

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "embree_glue/reference/embree_device.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/core/scene.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/bvh_stats.h"
#include "rebraid/top_level/two_level_builder.h"

namespace {

std::string g_scene_dir;

std::string default_scene_dir() {
    if (const char* env = std::getenv("REBRAID_SHARED_SCENES"); env && *env) return env;
    // Ninja and Make pass absolute source paths, so __FILE__ locates the repository.
    const std::filesystem::path from_source =
        std::filesystem::path(__FILE__).parent_path().parent_path() / ".." / "shared" / "scenes";
    if (std::filesystem::is_directory(from_source)) return from_source.lexically_normal();
    return "../shared/scenes";
}

/// Every instance's triangles transformed to world space as one mesh (what FlatAccel builds).
rebraid::Mesh flatten(const rebraid::Scene& scene) {
    rebraid::Mesh world;
    world.name = "world";
    for (const rebraid::Instance& instance : scene.instances) {
        const rebraid::Mesh& mesh = scene.meshes[instance.mesh_id];
        const auto base = std::uint32_t(world.positions.size());
        for (const rebraid::Vec3f& p : mesh.positions)
            world.positions.push_back(instance.object_to_world.transform_point(p));
        for (const rebraid::Triangle& t : mesh.triangles)
            world.triangles.push_back({base + t[0], base + t[1], base + t[2]});
    }
    return world;
}

/// World meshes by scene name, loaded on first use (the scene-dir flag is parsed by then).
const rebraid::Mesh& world_mesh(const std::string& name) {
    static std::map<std::string, rebraid::Mesh> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second;
    const rebraid::Scene scene = name == "default"
                                     ? rebraid::make_default_scene()
                                     : rebraid::load_gltf_scene(g_scene_dir + "/" + name);
    return cache.emplace(name, flatten(scene)).first->second;
}

void set_mprims_counter(benchmark::State& state, std::size_t prims) {
    state.counters["Mprims/s"] = benchmark::Counter(
        double(prims) * double(state.iterations()) * 1e-6, benchmark::Counter::kIsRate);
    state.counters["prims"] = double(prims);
}

/// build_object_bvh: build prims, tree, triangles copied into leaf order (manual time: the
/// SAH computed for the counter and freeing the BVH are excluded, as they are for Embree).
void own_object_build(benchmark::State& state, const std::string& scene) {
    const rebraid::Mesh* mesh = nullptr;
    try {
        mesh = &world_mesh(scene);
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
        return;
    }
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                std::size_t(state.range(0)));
    double sah = 0.0;
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        rebraid::ObjectBvh bvh = rebraid::build_object_bvh(*mesh);
        const auto stop = std::chrono::steady_clock::now();
        state.SetIterationTime(std::chrono::duration<double>(stop - start).count());
        sah = rebraid::object_bvh_sah(bvh);
    }
    set_mprims_counter(state, mesh->triangles.size());
    state.counters["sah"] = sah;
}

/// build_wide_bvh alone, on prepared build prims (manual time: the copy is excluded).
void own_tree_build(benchmark::State& state, const std::string& scene) {
    const rebraid::Mesh* mesh = nullptr;
    try {
        mesh = &world_mesh(scene);
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
        return;
    }
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                std::size_t(state.range(0)));
    const std::vector<rebraid::BuildPrim> source = rebraid::make_triangle_build_prims(*mesh);
    std::vector<rebraid::BuildPrim> prims;
    for (auto _ : state) {
        prims = source;
        const auto start = std::chrono::steady_clock::now();
        rebraid::WideBvh bvh = rebraid::build_wide_bvh(prims, {});
        const auto stop = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(bvh.nodes.data());
        state.SetIterationTime(std::chrono::duration<double>(stop - start).count());
    }
    set_mprims_counter(state, mesh->triangles.size());
}

/// rtcCommitScene of one triangle geometry holding the world mesh (manual time: filling
/// Embree's buffers is excluded, the commit builds Embree's prim refs, BVH and leaves).
void embree_scene_build(benchmark::State& state, const std::string& scene) {
    const rebraid::Mesh* mesh = nullptr;
    try {
        mesh = &world_mesh(scene);
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
        return;
    }
    const int thread_count = int(state.range(0));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                std::size_t(thread_count));
    rebraid::glue::EmbreeDevice device("threads=" + std::to_string(thread_count));
    for (auto _ : state) {
        RTCScene rtc_scene = rtcNewScene(device.get());
        rtcSetSceneBuildQuality(rtc_scene, RTC_BUILD_QUALITY_MEDIUM);
        RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree-allocated buffers are padded for its 16-byte vertex loads; copy into them.
        void* vertices =
            rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                    sizeof(rebraid::Vec3f), mesh->positions.size());
        std::memcpy(vertices, mesh->positions.data(),
                    mesh->positions.size() * sizeof(rebraid::Vec3f));
        void* indices =
            rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    sizeof(rebraid::Triangle), mesh->triangles.size());
        std::memcpy(indices, mesh->triangles.data(),
                    mesh->triangles.size() * sizeof(rebraid::Triangle));
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(rtc_scene, geometry);
        rtcReleaseGeometry(geometry);
        const auto start = std::chrono::steady_clock::now();
        rtcCommitScene(rtc_scene);
        const auto stop = std::chrono::steady_clock::now();
        state.SetIterationTime(std::chrono::duration<double>(stop - start).count());
        rtcReleaseScene(rtc_scene);
        try {
            device.throw_if_error("rtcCommitScene");
        } catch (const std::exception& e) {
            state.SkipWithError(e.what());
            return;
        }
    }
    set_mprims_counter(state, mesh->triangles.size());
}

/// A scene with its object BVHs, for the top-level benchmarks.
struct SceneWithObjects {
    rebraid::Scene scene;
    std::vector<rebraid::ObjectBvh> object_bvhs;
};

/// Scenes by name ("default", a shared scene's file name, or a path), loaded and their object
/// BVHs built on first use.
const SceneWithObjects& scene_with_objects(const std::string& name) {
    static std::map<std::string, SceneWithObjects> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second;
    SceneWithObjects loaded;
    if (name == "default")
        loaded.scene = rebraid::make_default_scene();
    else
        loaded.scene = rebraid::load_gltf_scene(
            name.find('/') == std::string::npos ? g_scene_dir + "/" + name : name);
    loaded.object_bvhs =
        rebraid::build_object_bvhs(loaded.scene, rebraid::own_object_bvh_builder());
    return cache.emplace(name, std::move(loaded)).first->second;
}

double process_cpu_seconds() {
    timespec now{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

/// Which top level a benchmark builds: the plain top, the paper's rules, the paper's rules
/// with the sah opening rule, and the project's defaults (sah opening, vertex bounds).
enum class TopKind { two_level, rebraid_paper, rebraid_sah, rebraid_default };

/// One top-level build per iteration (manual time: the build call alone).
void top_build(benchmark::State& state, const std::string& scene, TopKind kind) {
    const SceneWithObjects* input = nullptr;
    try {
        input = &scene_with_objects(scene);
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
        return;
    }
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                std::size_t(state.range(0)));
    rebraid::RebraidSettings settings = kind == TopKind::rebraid_default
                                            ? rebraid::RebraidSettings{}
                                            : rebraid::RebraidSettings::paper_rules();
    if (kind == TopKind::rebraid_sah) settings.opening_rule = rebraid::OpeningRule::sah;
    std::size_t items = 0;
    double seconds = 0.0;
    double min_wall = std::numeric_limits<double>::infinity(), min_cpu = min_wall;
    for (auto _ : state) {
        const double cpu_start = process_cpu_seconds();
        const auto start = std::chrono::steady_clock::now();
        if (kind == TopKind::two_level) {
            const rebraid::TopLevelBvh top =
                rebraid::build_two_level(input->scene, input->object_bvhs);
            items = top.items.size();
        } else {
            const rebraid::RebraidBuild build =
                rebraid::build_rebraid(input->scene, input->object_bvhs, settings);
            items = build.top.items.size();
        }
        const auto stop = std::chrono::steady_clock::now();
        const double cpu = process_cpu_seconds() - cpu_start;
        const double elapsed = std::chrono::duration<double>(stop - start).count();
        state.SetIterationTime(elapsed);
        seconds += elapsed;
        min_wall = std::min(min_wall, elapsed);
        min_cpu = std::min(min_cpu, cpu);
    }
    state.counters["items"] = double(items);
    // The fastest single build, in wall time and in CPU time of the whole process (other
    // load on a shared machine stretches wall times; on one thread the CPU time stays near
    // the idle figure, on two it adds the workers' spinning).
    state.counters["min_ms"] = min_wall * 1e3;
    state.counters["min_cpu_ms"] = min_cpu * 1e3;
    // From the measured wall time (rate counters divide by the main thread's CPU time).
    if (items > 0 && state.iterations() > 0)
        state.counters["ns/item"] = seconds * 1e9 / double(state.iterations()) / double(items);
}

std::vector<std::string> g_top_scenes = {"default", "cg57_cruiser.glb"};

void register_top_benchmarks() {
    const std::pair<const char*, TopKind> kinds[] = {
        {"TopBuild/twolevel/", TopKind::two_level},
        {"TopBuild/paper/", TopKind::rebraid_paper},
        {"TopBuild/sah/", TopKind::rebraid_sah},
        {"TopBuild/default/", TopKind::rebraid_default}};
    for (const std::string& scene : g_top_scenes)
        for (const auto& [prefix, kind] : kinds) {
            const std::string label = std::filesystem::path(scene).filename().string();
            benchmark::RegisterBenchmark(
                (prefix + label).c_str(),
                [scene, kind = kind](benchmark::State& s) { top_build(s, scene, kind); })
                ->Arg(1)
                ->Arg(2)
                ->ArgName("threads")
                ->Unit(benchmark::kMillisecond)
                ->UseManualTime()
                ->ComputeStatistics("min", [](const std::vector<double>& v) {
                    return *std::min_element(v.begin(), v.end());
                });
        }
}

void register_benchmarks() {
    using Measure = void (*)(benchmark::State&, const std::string&);
    const std::pair<const char*, Measure> measures[] = {{"OwnObjectBuild/", own_object_build},
                                                        {"OwnTreeBuild/", own_tree_build},
                                                        {"EmbreeSceneBuild/", embree_scene_build}};
    for (const char* scene : {"default", "cg57_cruiser.glb"})
        for (const auto& [prefix, measure] : measures) {
            const std::string name = scene;
            benchmark::RegisterBenchmark(
                (prefix + name).c_str(),
                [name, measure = measure](benchmark::State& s) { measure(s, name); })
                ->Arg(1)
                ->Arg(2)
                ->ArgName("threads")
                ->Unit(benchmark::kMillisecond)
                ->UseManualTime();
        }
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    g_scene_dir = default_scene_dir();
    for (int i = 1; i < argc; ++i) {
        constexpr const char* kFlag = "--scene-dir=";
        constexpr const char* kTopFlag = "--top-scene=";
        if (std::strncmp(argv[i], kTopFlag, std::strlen(kTopFlag)) == 0) {
            g_top_scenes.push_back(argv[i] + std::strlen(kTopFlag));
        } else if (std::strncmp(argv[i], kFlag, std::strlen(kFlag)) == 0) {
            g_scene_dir = argv[i] + std::strlen(kFlag);
        } else if (std::strcmp(argv[i], "--scene-dir") == 0 && i + 1 < argc) {
            g_scene_dir = argv[++i];
        } else {
            std::fprintf(stderr,
                         "bench_build: unknown argument '%s' (expected --scene-dir=DIR or "
                         "--top-scene=FILE)\n",
                         argv[i]);
            return 1;
        }
    }
    register_benchmarks();
    register_top_benchmarks();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
