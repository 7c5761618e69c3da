// `rebraid bench [SCENE...] --accel LIST`: per scene, build each structure and measure build
// time, SAH and closest-hit Mrays/s on the same primary and diffuse-bounce rays.
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "accel_factory.h"
#include "bench_rays.h"
#include "commands.h"
#include "embree_glue/reference/embree_ray_batch.h"
#include "embree_glue/reference/embree_reference.h"
#include "option_checks.h"
#include "output_file.h"
#include "rebraid/io/ray_file.h"
#include "scene_source.h"
#include "stats_json.h"
#include "status_line.h"

namespace rebraid::cli {

namespace {

/// A SCENE argument naming the built-in default scene, so it can be listed among files.
constexpr const char* kDefaultSceneToken = "default";

struct BenchOptions {
    std::vector<std::string> scene_paths;  ///< none: the default scene
    std::vector<std::string> accel_names = cli::accel_names();
    AccelOptions accel_options;
    BenchRaySettings rays;
    int repetitions = 5;
    bool is_json = false;
    /// Folder the rays are written to, or empty (see --save-rays).
    std::string save_rays_dir;
    /// Build, time and free each structure in turn (see --one-at-a-time).
    bool one_at_a_time = false;
};

/// The ray files --save-rays writes for the scene at `path` (empty: the default scene):
/// DIR/NAME.primary.rays and DIR/NAME.diffuse.rays, NAME the file's stem.
std::pair<std::string, std::string> saved_ray_paths(const std::string& dir,
                                                    const std::string& path) {
    const std::string name =
        path.empty() ? std::string("default") : std::filesystem::path(path).stem().string();
    const std::filesystem::path base = std::filesystem::path(dir) / name;
    return {base.string() + ".primary.rays", base.string() + ".diffuse.rays"};
}

/// Closest-hit throughput of one structure on one ray set.
struct TraceTiming {
    double mrays_per_second = 0.0;
    std::size_t hit_count = 0;
};

/// The median of `seconds` (not empty).
double median_of(std::vector<double> seconds) {
    std::sort(seconds.begin(), seconds.end());
    const std::size_t middle = seconds.size() / 2;
    return seconds.size() % 2 == 1 ? seconds[middle]
                                   : 0.5 * (seconds[middle - 1] + seconds[middle]);
}

/// Closest-hit throughput of each of `accels` on `rays`: the structures take turns, each
/// tracing the rays (in parallel) once to warm up (caches, page faults, TBB's workers) and once
/// timed, `repetitions` times, and each one's median time gives its rate. Taking turns, a
/// machine whose speed drifts during the measurement (another tenant, the clock) slows every
/// structure alike, where timing one structure after the other moved their ratios by up to a
/// fifth between processes. Each structure is queried as its users query it: the project's
/// through Accel::intersect, Embree's by rtcIntersect1 on rays already in its layout
/// (glue::EmbreeRayBatch, converted before the timing: the Accel wrapper's conversions would
/// count against Embree). Not inlined, so profilers can attribute each call to its ray set
/// (e.g. valgrind --dump-after=*time_closest_hits* writes one profile per call: primary, then
/// diffuse).
[[gnu::noinline]] std::vector<TraceTiming> time_closest_hits(
    const std::vector<const Accel*>& accels, const std::vector<Ray>& rays, int repetitions) {
    std::vector<TraceTiming> timings(accels.size());
    if (rays.empty()) return timings;
    struct Timed {
        const Accel& accel;
        std::vector<Hit> hits;  // written, so no trace can be optimised away
        std::optional<glue::EmbreeRayBatch> embree_rays;
        std::vector<double> seconds;
    };
    std::vector<Timed> timed;
    timed.reserve(accels.size());
    for (const Accel* accel : accels) {
        Timed& entry = timed.emplace_back(Timed{*accel, std::vector<Hit>(rays.size()), {}, {}});
        if (glue::EmbreeRayBatch::serves(*accel)) entry.embree_rays.emplace(*accel, rays);
    }
    const auto trace_once = [&rays](Timed& entry) {
        const auto start = std::chrono::steady_clock::now();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 64),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              if (entry.embree_rays) {
                                  entry.embree_rays->intersect(range.begin(), range.end());
                                  return;
                              }
                              for (std::size_t i = range.begin(); i != range.end(); ++i)
                                  entry.hits[i] = entry.accel.intersect(rays[i]);
                          });
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    // Each timed pass follows an untimed one of the same structure: it finds the structure in
    // the caches, as a structure timed alone does, instead of what the one before it left.
    for (int i = 0; i < repetitions; ++i)
        for (Timed& entry : timed) {
            trace_once(entry);
            entry.seconds.push_back(trace_once(entry));
        }
    for (std::size_t a = 0; a < timed.size(); ++a) {
        Timed& entry = timed[a];
        if (entry.embree_rays)
            for (std::size_t i = 0; i < rays.size(); ++i) entry.hits[i] = entry.embree_rays->hit(i);
        TraceTiming& timing = timings[a];
        timing.mrays_per_second =
            static_cast<double>(rays.size()) / std::max(median_of(entry.seconds), 1e-9) / 1e6;
        timing.hit_count = static_cast<std::size_t>(std::count_if(
            entry.hits.begin(), entry.hits.end(), [](const Hit& hit) { return hit.is_hit(); }));
    }
    return timings;
}

/// Work per ray of one structure on one ray set, counted in an untimed pass
/// (Accel::intersect_counted): the deterministic side of a speed difference.
struct TraceWork {
    double nodes_per_ray = 0.0;
    double triangles_per_ray = 0.0;
    double object_entries_per_ray = 0.0;
};

/// Counts the work of closest-hit queries for `rays`, one after the other (the sums do not
/// depend on the thread count). Empty for Embree's structures, which count nothing.
std::optional<TraceWork> count_closest_hit_work(const Accel& accel, const std::vector<Ray>& rays) {
    TraversalCounters counters;
    for (const Ray& ray : rays) accel.intersect_counted(ray, &counters);
    if (rays.empty() || counters.nodes_visited + counters.triangles_tested == 0) return {};
    const double count = static_cast<double>(rays.size());
    return TraceWork{static_cast<double>(counters.nodes_visited) / count,
                     static_cast<double>(counters.triangles_tested) / count,
                     static_cast<double>(counters.object_entries) / count};
}

/// What one structure measured on one scene.
struct BenchResult {
    std::string scene;
    const AccelVariant* variant = nullptr;
    AccelStats stats;
    TraceTiming primary, diffuse;
    std::optional<TraceWork> diffuse_work;
};

std::size_t active_thread_count() {
    return tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
}

nlohmann::ordered_json result_to_json(const BenchResult& result, const BenchRays& rays,
                                      const BenchOptions& options) {
    nlohmann::ordered_json json;
    json["scene"] = result.scene;
    // The whole NAME[:KEY=VALUE...] text: variants of one structure stay apart.
    json["accel"] = result.variant->label;
    if (result.variant->entry->has_object_bvhs)
        json["object_builder"] = object_builder_name(result.variant->options.object_builder);
    json.update(stats_to_json(result.stats));
    if (!result.stats.sah) json["sah"] = nullptr;  // Embree's own BVHs are not inspectable
    json["mrays_primary"] = result.primary.mrays_per_second;
    json["mrays_diffuse"] = result.diffuse.mrays_per_second;
    json["rays_primary"] = rays.primary.size();
    json["rays_diffuse"] = rays.diffuse.size();
    json["hits_primary"] = result.primary.hit_count;
    json["hits_diffuse"] = result.diffuse.hit_count;
    // Work per diffuse ray: null where the structure cannot count it (Embree's).
    const auto work_field = [&](double TraceWork::*field) {
        return result.diffuse_work ? nlohmann::ordered_json(*result.diffuse_work.*field)
                                   : nlohmann::ordered_json(nullptr);
    };
    json["nodes_per_diffuse_ray"] = work_field(&TraceWork::nodes_per_ray);
    json["triangles_per_diffuse_ray"] = work_field(&TraceWork::triangles_per_ray);
    json["object_entries_per_diffuse_ray"] = work_field(&TraceWork::object_entries_per_ray);
    json["threads"] = active_thread_count();
    json["repetitions"] = options.repetitions;
    json["timing"] = options.one_at_a_time ? "one_at_a_time" : "taking_turns";
    return json;
}

void print_scene_header(const std::string& scene_name, const Scene& scene, const BenchRays& rays,
                        const BenchOptions& options, int name_width) {
    std::printf(
        "%s: %llu triangles, %zu instances, %zu meshes; %zu primary rays (%dx%d, %zu hit) and "
        "%zu diffuse rays; %zu threads; Mrays/s from the median of %d runs, each after a warm-up "
        "run, %s\n",
        scene_name.c_str(), static_cast<unsigned long long>(scene.instanced_triangle_count()),
        scene.instances.size(), scene.meshes.size(), rays.primary.size(), rays.image_width,
        rays.image_height, rays.primary_hit_count, rays.diffuse.size(), active_thread_count(),
        options.repetitions,
        options.one_at_a_time ? "each structure alone" : "the structures taking turns");
    std::printf("  %-*s %10s %10s %8s %10s %10s %10s %10s\n", name_width, "accel", "build_ms",
                "top_ms", "sah", "nodes", "memory_MB", "Mrays_pri", "Mrays_dif");
}

/// The name a table row shows: the variant's label, plus the object builder when not ours.
std::string row_name(const AccelVariant& variant) {
    std::string name = variant.label;
    if (variant.entry->has_object_bvhs && variant.options.object_builder != ObjectBuilderKind::own)
        name += "/" + std::string(object_builder_name(variant.options.object_builder));
    return name;
}

void print_result_row(const BenchResult& result, int name_width) {
    const AccelStats& stats = result.stats;
    const std::string name = row_name(*result.variant);
    const auto optional_number = [](auto value, const char* format) {
        if (!value) return std::string("-");
        char text[32];
        std::snprintf(text, sizeof text, format, static_cast<double>(*value));
        return std::string(text);
    };
    std::optional<double> memory_mb;
    if (stats.memory_bytes) memory_mb = static_cast<double>(*stats.memory_bytes) / (1 << 20);
    std::printf("  %-*s %10.1f %10s %8s %10s %10s %10.2f %10.2f\n", name_width, name.c_str(),
                stats.build_ms, optional_number(stats.top_build_ms, "%.1f").c_str(),
                optional_number(stats.sah, "%.2f").c_str(),
                optional_number(stats.nodes, "%.0f").c_str(),
                optional_number(memory_mb, "%.1f").c_str(), result.primary.mrays_per_second,
                result.diffuse.mrays_per_second);
    std::fflush(stdout);
}

void run_bench(const BenchOptions& options) {
    // Check every name, setting and scene file before the first (slow) scene load.
    options.accel_options.rebraid.validate();
    check_build_options_used(options.accel_names, options.accel_options);
    std::vector<AccelVariant> variants;
    int name_width = 18;
    for (const std::string& name : options.accel_names) {
        variants.push_back(parse_accel_variant(name, options.accel_options));
        name_width = std::max(name_width, int(row_name(variants.back()).size()));
    }
    check_variants_differ(variants);

    std::vector<std::string> scene_paths = options.scene_paths;
    if (scene_paths.empty()) scene_paths.emplace_back();
    for (std::string& path : scene_paths) {
        if (path == kDefaultSceneToken) path.clear();  // load_scene's name for it
        check_scene_file(path);
        if (!options.save_rays_dir.empty()) {
            const auto [primary, diffuse] = saved_ray_paths(options.save_rays_dir, path);
            check_output_file(primary, "ray file");
            check_output_file(diffuse, "ray file");
        }
    }
    nlohmann::ordered_json all_results = nlohmann::ordered_json::array();
    StatusLine status;
    for (std::size_t scene_index = 0; scene_index < scene_paths.size(); ++scene_index) {
        const std::string& path = scene_paths[scene_index];
        const std::string scene_name = describe_scene(path);
        const std::string scene_step = "bench: scene " + std::to_string(scene_index + 1) + "/" +
                                       std::to_string(scene_paths.size()) + " (" + scene_name + ")";
        status.show(scene_step + ": loading");
        const Scene scene = load_scene(path);
        status.show(scene_step + ": making rays");
        BenchRays rays;
        {
            // Embree's instanced scene finds the hit points: it fits in memory for every
            // scene, even those whose flattened form does not.
            const glue::EmbreeInstancedAccel reference(scene);
            rays = make_bench_rays(scene, reference, options.rays);
        }
        if (!options.save_rays_dir.empty()) {
            const auto [primary, diffuse] = saved_ray_paths(options.save_rays_dir, path);
            write_output(primary, [&](std::ostream& out) { write_rays(out, rays.primary); });
            write_output(diffuse, [&](std::ostream& out) { write_rays(out, rays.diffuse); });
        }
        status.clear();
        if (!options.is_json) print_scene_header(scene_name, scene, rays, options, name_width);
        const auto step_of = [&](std::size_t v) {
            return scene_step + ", " + variants[v].label + " (" + std::to_string(v + 1) + "/" +
                   std::to_string(variants.size()) + "): ";
        };
        // Builds the variants [first, end), times them taking turns, counts their work, reports
        // them and frees them: all at once, or each alone (--one-at-a-time).
        const auto measure = [&](std::size_t first, std::size_t end) {
            std::vector<BenchResult> results;
            std::vector<std::unique_ptr<Accel>> accels;
            std::vector<const Accel*> timed;
            for (std::size_t v = first; v < end; ++v) {
                status.show(step_of(v) + "building");
                accels.push_back(variants[v].entry->build(scene, variants[v].options));
                results.push_back(
                    BenchResult{scene_name, &variants[v], accels.back()->stats(), {}, {}, {}});
                timed.push_back(accels.back().get());
            }
            const std::string timing_step =
                end - first == 1 ? step_of(first) : scene_step + ", the structures taking turns: ";
            status.show(timing_step + "timing primary rays");
            const std::vector<TraceTiming> primary =
                time_closest_hits(timed, rays.primary, options.repetitions);
            status.show(timing_step + "timing diffuse rays");
            const std::vector<TraceTiming> diffuse =
                time_closest_hits(timed, rays.diffuse, options.repetitions);
            for (std::size_t i = 0; i < results.size(); ++i) {
                results[i].primary = primary[i];
                results[i].diffuse = diffuse[i];
                if (options.is_json) {
                    status.show(step_of(first + i) + "counting work per ray");
                    results[i].diffuse_work = count_closest_hit_work(*accels[i], rays.diffuse);
                }
            }
            accels.clear();  // freed before any other structure is built
            status.clear();
            for (const BenchResult& result : results) {
                if (options.is_json)
                    all_results.push_back(result_to_json(result, rays, options));
                else
                    print_result_row(result, name_width);
            }
        };
        if (options.one_at_a_time) {
            for (std::size_t v = 0; v < variants.size(); ++v) measure(v, v + 1);
        } else {
            measure(0, variants.size());
        }
    }
    if (options.is_json) std::cout << all_results.dump(2) << "\n";
}

}  // namespace

void add_bench_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<BenchOptions>();
    CLI::App* command = app.add_subcommand(
        "bench",
        "Per scene, build each structure and measure, on the same rays, its build time, SAH and "
        "closest-hit Mrays/s for primary camera rays and for incoherent diffuse-bounce rays.");
    command
        ->add_option("SCENE", options->scene_paths,
                     "scene files (.gltf/.glb); 'default' names the built-in default scene, "
                     "which is also used when no scene is given")
        ->type_name("PATH...");
    std::string default_accels;
    for (const std::string& name : options->accel_names)
        default_accels += (default_accels.empty() ? "" : ",") + name;
    command
        ->add_option("--accel", options->accel_names,
                     "comma-separated structures, from: " + accel_names_joined() + " (default " +
                         default_accels +
                         "); NAME:KEY=VALUE[:KEY=VALUE...] is a variant with its own build "
                         "options, named so in the output, e.g. "
                         "twolevel,rebraid,rebraid:opening=sah:bref-bounds=children; keys: " +
                         accel_variant_keys())
        ->delimiter(',')
        ->type_name("LIST");
    command
        ->add_option("--rays", options->rays.ray_count,
                     "primary rays, one per pixel of a 16:9 image; as many diffuse rays")
        ->check(whole_number(1, std::int64_t{1} << 30))
        ->capture_default_str()
        ->type_name("N");
    command
        ->add_option("--repetitions", options->repetitions,
                     "timed runs per ray set, each after an untimed warm-up run; the median counts")
        ->check(whole_number(1, 1000))
        ->capture_default_str();
    command->add_option("--seed", options->rays.seed, "seed of the diffuse directions")
        ->check(whole_number(0, std::numeric_limits<std::int64_t>::max()))
        ->capture_default_str();
    command->add_flag("--one-at-a-time", options->one_at_a_time,
                      "build, time and free each structure before the next is built, for "
                      "scenes whose structures do not fit in memory together (default: all are "
                      "built first, then timed taking turns, so that a drift in the machine's "
                      "speed slows each alike)");
    command->add_flag("--json", options->is_json,
                      "print one JSON array: an object per scene and structure (scene, accel, "
                      "build_ms, sah, mrays_primary, mrays_diffuse, the stats fields, nodes, "
                      "triangles and object entries per diffuse ray, ...)");
    command
        ->add_option("--save-rays", options->save_rays_dir,
                     "also write each scene's primary and diffuse rays to DIR/NAME.primary.rays "
                     "and DIR/NAME.diffuse.rays (NAME: the scene file's stem, or 'default'), to "
                     "trace the same rays again with 'rebraid trace'")
        ->type_name("DIR");
    add_accel_build_options(*command, options->accel_options);
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_bench(*options); }; });
}

}  // namespace rebraid::cli
