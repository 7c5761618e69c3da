// Updating the BVH of a deforming mesh: time per frame and SAH per update strategy
// (ObjectBvhUpdater) over an animation of N frames, at 1 and 2 threads.
//
// Scenes: "twist" (a welded torus knot of 131k triangles twisted and bent: coherent motion,
// what refitting handles well) and "explode" (the same knot with its triangles unwelded,
// each flying off along its own direction: incoherent motion, the case rotations and
// restructuring are for).
//
// Usage: bench_update [--frames=N] [Google Benchmark flags, e.g.
//        --benchmark_filter=explode --benchmark_counters_tabular=true]
// Time is the mean update time per frame (manual time; making the frame's positions and
// computing the SAH counters are excluded). Counters: sah (after the last frame), sah_mean
// (over the frames), vs_rebuild (sah over the SAH of a fresh build of the last frame),
// rebuilds (frames on which the strategy rebuilt), repairs (frames on which auto ran its
// repair pass), cpu_ms (process CPU time per frame of the updates alone: at 1 thread the
// figure least disturbed by other work on the machine). rotate is the default rotation pass
// (split_merge leaves, two moves per node, a node searched once its children grew 1 %:
// RotationSettings); rotate_no_search is that pass without its move search, rotate_eager
// searches every node every pass, rotate_one_per_node applies one move per node;
// rotate_pre_split is Kopta's schedule (one triangle per leaf, one move, every node every
// pass) and rotate_pre_split_lazy the same searching at 1 % growth; refit_pre_split is a refit
// of the one-triangle-per-leaf tree; restructure_rotates runs the rotation pass
// instead of a plain refit before restructuring; treelet_pre_split samples treelets in a
// tree of one triangle per leaf (default root_fraction, or 0.2);
// auto_<repair> is auto with that repair between its two factors (plain auto: refit only).

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/random.h"
#include "rebraid/dynamic/object_bvh_update.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/top_level/bvh_stats.h"

namespace {

int g_frame_count = 100;

/// The knot every scene deforms: 2 * 2048 * 32 = 131072 triangles.
rebraid::Mesh knot() {
    return rebraid::make_torus_knot({.path_segment_count = 2048, .tube_segment_count = 32});
}

/// A deforming mesh: the rest pose and the positions at any time t in [0, 1].
class Animation {
public:
    virtual ~Animation() = default;
    virtual const rebraid::Mesh& rest() const = 0;
    virtual void pose(float t, rebraid::Mesh& mesh) const = 0;
};

/// Twist about Y (up to 2 radians per unit of height) and a bend about Z.
class TwistAnimation final : public Animation {
public:
    TwistAnimation() : rest_(knot()) {}
    const rebraid::Mesh& rest() const override { return rest_; }
    void pose(float t, rebraid::Mesh& mesh) const override {
        for (std::size_t i = 0; i < rest_.positions.size(); ++i) {
            const rebraid::Vec3f p = rest_.positions[i];
            const float twist = 2.0f * t * p.y;
            const float x = std::cos(twist) * p.x + std::sin(twist) * p.z;
            const float z = -std::sin(twist) * p.x + std::cos(twist) * p.z;
            const float bend = 0.6f * t * x;
            mesh.positions[i] = {std::cos(bend) * x - std::sin(bend) * p.y,
                                 std::sin(bend) * x + std::cos(bend) * p.y, z};
        }
    }

private:
    rebraid::Mesh rest_;
};

/// Unwelded triangles, each moving rigidly along its own random direction at its own speed
/// (up to 1.5 knot radii by t = 1), like the exploding-dragon animation of the papers.
class ExplodeAnimation final : public Animation {
public:
    ExplodeAnimation() {
        const rebraid::Mesh welded = knot();
        rebraid::Random random(2024);
        for (std::uint32_t prim = 0; prim < welded.triangles.size(); ++prim) {
            const auto base = std::uint32_t(rest_.positions.size());
            for (const rebraid::Vec3f& corner : welded.corners(prim))
                rest_.positions.push_back(corner);
            rest_.triangles.push_back({base, base + 1, base + 2});
            velocity_.push_back(rebraid::Vec3f{random.next_float(-1, 1), random.next_float(-1, 1),
                                               random.next_float(-1, 1)} *
                                random.next_float(0.0f, 1.5f));
        }
    }
    const rebraid::Mesh& rest() const override { return rest_; }
    void pose(float t, rebraid::Mesh& mesh) const override {
        for (std::size_t prim = 0; prim < rest_.triangles.size(); ++prim)
            for (std::uint32_t vertex : rest_.triangles[prim])
                mesh.positions[vertex] = rest_.positions[vertex] + velocity_[prim] * t;
    }

private:
    rebraid::Mesh rest_;
    std::vector<rebraid::Vec3f> velocity_;
};

/// CPU time of the whole process so far, in milliseconds.
double process_cpu_ms() {
    timespec now{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return double(now.tv_sec) * 1e3 + double(now.tv_nsec) * 1e-6;
}

const Animation& animation(const std::string& name) {
    static const TwistAnimation twist;
    static const ExplodeAnimation explode;
    return name == "twist" ? static_cast<const Animation&>(twist) : explode;
}

struct Variant {
    std::string name;
    rebraid::ObjectBvhUpdateSettings settings;
};

std::vector<Variant> variants() {
    using rebraid::UpdateStrategy;
    std::vector<Variant> list;
    for (UpdateStrategy strategy : rebraid::kUpdateStrategies) {
        rebraid::ObjectBvhUpdateSettings settings;
        settings.strategy = strategy;
        list.push_back({std::string(rebraid::update_strategy_name(strategy)), settings});
        if (strategy == UpdateStrategy::restructure) {
            settings.restructure_rotates = true;
            list.push_back({"restructure_rotates", settings});
            settings.restructure_rotates = false;
        }
        if (strategy == UpdateStrategy::treelet) {
            settings.build.max_leaf_size = 1;
            list.push_back({"treelet_pre_split", settings});
            settings.treelet.root_fraction = 0.2;
            list.push_back({"treelet_pre_split_0.2", settings});
            settings.build = {};
            settings.treelet = {};
        }
        if (strategy == UpdateStrategy::refit) {
            settings.build.max_leaf_size = 1;
            list.push_back({"refit_pre_split", settings});
            settings.build = {};
        }
        if (strategy == UpdateStrategy::rotate) {
            // The default: split_merge, two moves per node, lazy search (1 % growth).
            settings.rotation.max_rotations_per_node = 0;
            list.push_back({"rotate_no_search", settings});
            settings.rotation = {};
            settings.rotation.min_growth_to_search = 0.0f;
            list.push_back({"rotate_eager", settings});
            settings.rotation = {};
            settings.rotation.max_rotations_per_node = 1;
            list.push_back({"rotate_one_per_node", settings});
            // Kopta's schedule: one triangle per leaf, one move per node, every node.
            settings.rotation = {};
            settings.rotation.leaf_mode = rebraid::RotationLeafMode::pre_split;
            settings.rotation.max_rotations_per_node = 1;
            settings.rotation.min_growth_to_search = 0.0f;
            list.push_back({"rotate_pre_split", settings});
            settings.rotation.min_growth_to_search = 0.01f;
            list.push_back({"rotate_pre_split_lazy", settings});
            settings.rotation = {};
        }
        if (strategy == UpdateStrategy::automatic) {
            for (UpdateStrategy repair :
                 {UpdateStrategy::treelet, UpdateStrategy::restructure, UpdateStrategy::rotate}) {
                settings.auto_repair = repair;
                list.push_back(
                    {"auto_" + std::string(rebraid::update_strategy_name(repair)), settings});
            }
        }
    }
    return list;
}

void run_animation(benchmark::State& state, const std::string& scene, const Variant& variant) {
    const Animation& anim = animation(scene);
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                std::size_t(state.range(0)));
    rebraid::Mesh mesh = anim.rest();
    double total_ms = 0.0, sah_sum = 0.0, sah = 0.0, cpu_ms = 0.0;
    int rebuilds = 0, repairs = 0;
    for (auto _ : state) {
        rebraid::ObjectBvhUpdater updater(variant.settings);
        rebraid::ObjectBvh bvh = rebraid::build_object_bvh(anim.rest(), updater.rebuild_settings());
        total_ms = sah_sum = cpu_ms = 0.0;
        rebuilds = repairs = 0;
        for (int frame = 1; frame <= g_frame_count; ++frame) {
            anim.pose(float(frame) / float(g_frame_count), mesh);
            const double cpu_before = process_cpu_ms();
            const rebraid::ObjectBvhUpdateReport report = updater.update(mesh, bvh);
            cpu_ms += process_cpu_ms() - cpu_before;
            total_ms += report.update_ms;
            repairs += variant.settings.strategy == rebraid::UpdateStrategy::automatic &&
                       report.applied != rebraid::UpdateStrategy::rebuild &&
                       report.applied != rebraid::UpdateStrategy::refit;
            sah_sum += report.sah;
            sah = report.sah;
            rebuilds += report.applied == rebraid::UpdateStrategy::rebuild;
        }
        state.SetIterationTime(total_ms * 1e-3 / g_frame_count);
    }
    const double fresh_sah = rebraid::object_bvh_sah(rebraid::build_object_bvh(mesh));
    state.counters["sah"] = sah;
    state.counters["sah_mean"] = sah_sum / g_frame_count;
    state.counters["vs_rebuild"] = sah / fresh_sah;
    state.counters["rebuilds"] = rebuilds;
    state.counters["repairs"] = repairs;
    state.counters["cpu_ms"] = cpu_ms / g_frame_count;
    state.counters["tris"] = double(mesh.triangles.size());
}

void register_benchmarks() {
    for (const char* scene : {"twist", "explode"}) {
        for (const Variant& variant : variants()) {
            const std::string name = std::string(scene) + "/" + variant.name;
            benchmark::RegisterBenchmark(
                name.c_str(), [scene = std::string(scene),
                               variant](benchmark::State& s) { run_animation(s, scene, variant); })
                ->Arg(1)
                ->Arg(2)
                ->ArgName("threads")
                ->Iterations(1)
                ->Unit(benchmark::kMillisecond)
                ->UseManualTime();
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    for (int i = 1; i < argc; ++i) {
        constexpr const char* kFlag = "--frames=";
        if (std::strncmp(argv[i], kFlag, std::strlen(kFlag)) == 0 &&
            std::atoi(argv[i] + std::strlen(kFlag)) > 0) {
            g_frame_count = std::atoi(argv[i] + std::strlen(kFlag));
        } else {
            std::fprintf(stderr, "bench_update: unknown argument '%s' (expected --frames=N)\n",
                         argv[i]);
            return 1;
        }
    }
    const rebraid::ObjectBvhUpdateSettings defaults;
    benchmark::AddCustomContext("frames", std::to_string(g_frame_count));
    benchmark::AddCustomContext("rebuild_sah_factor", std::to_string(defaults.rebuild_sah_factor));
    benchmark::AddCustomContext("repair_sah_factor", std::to_string(defaults.repair_sah_factor));
    benchmark::AddCustomContext(
        "treelet",
        "root_fraction=" + std::to_string(defaults.treelet.root_fraction) +
            " max_treelet_leaves=" + std::to_string(defaults.treelet.max_treelet_leaves));
    benchmark::AddCustomContext(
        "restructure",
        "max_rebuilt_fraction=" + std::to_string(defaults.restructure.max_rebuilt_fraction) +
            " min_subtree_prims=" + std::to_string(defaults.restructure.min_subtree_prims));
    register_benchmarks();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
