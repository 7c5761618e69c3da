// `rebraid animate`: the dynamic-in-static frame benchmark. Copies of an animated
// object stand in a static scene; every frame poses them, brings each method's structure up
// to date and renders one frame (primary rays plus one diffuse bounce) through it.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "accel_factory.h"
#include "animate_output.h"
#include "bench_rays.h"
#include "commands.h"
#include "embree_glue/reference/embree_dynamic_scene.h"
#include "embree_glue/reference/embree_ray_batch.h"
#include "option_checks.h"
#include "output_file.h"
#include "rebraid/core/error.h"
#include "rebraid/dynamic/dynamic_scene.h"
#include "rebraid/dynamic/dynamic_scene_accel.h"
#include "rebraid/generators/twisting_object.h"
#include "rebraid/io/gltf_dynamic_object.h"
#include "rebraid/render/progress.h"
#include "scene_source.h"

namespace rebraid::cli {

namespace {

struct AnimateOptions {
    std::string static_path;   ///< empty: the default scene
    std::string dynamic_path;  ///< empty: the built-in twisting object
    std::size_t copy_count = 4;
    int frame_count = 30;
    float time_step = 1.0f / 30.0f;
    std::vector<std::string> update_names;  ///< empty: every strategy
    std::vector<std::string> top_names;     ///< empty: all three
    float budget_factor = RebraidSettings{}.budget_factor;
    std::uint32_t max_cut_pieces = IncrementalTopSettings{}.max_cut_pieces;
    bool has_embree = true;
    ObjectBuilderKind static_builder = ObjectBuilderKind::own;
    int width = 640;
    int height = 360;
    std::uint64_t seed = 1;
    float size_fraction = 0.15f;
    bool is_json = false;
    std::string csv_path;
    std::string plot_path;
};

/// One way of following the animation, as the benchmark measures it.
class AnimateMethod {
public:
    virtual ~AnimateMethod() = default;
    virtual const std::string& name() const = 0;
    virtual double build_ms() const = 0;
    /// Brings the structure to the scene's current pose; fills update_ms, top_ms and sah.
    virtual void update(AnimateFrameRow& row) = 0;
    virtual const Accel& accel() const = 0;
};

class EmbreeMethod final : public AnimateMethod {
public:
    // Embree's default scene flags (not RTC_SCENE_FLAG_ROBUST), as an Embree application that
    // sets none gets them.
    EmbreeMethod(const DynamicScene& scene, glue::EmbreeDynamicMode mode)
        : name_(glue::embree_dynamic_mode_name(mode)),
          accel_(scene, mode,
                 glue::EmbreeReferenceSettings{.is_robust = false, .device_config = {}}) {}
    const std::string& name() const override { return name_; }
    double build_ms() const override { return accel_.stats().build_ms; }
    void update(AnimateFrameRow& row) override {
        const glue::EmbreeFrameTimes times = accel_.update();
        row.update_ms = times.update_ms;
        row.top_ms = times.top_ms;
        row.sah.reset();  // Embree's trees cannot be inspected
    }
    const Accel& accel() const override { return accel_; }

private:
    std::string name_;
    glue::EmbreeDynamicAccel accel_;
};

class OwnMethod final : public AnimateMethod {
public:
    OwnMethod(const DynamicScene& scene, const DynamicSceneAccelSettings& settings)
        : name_(std::string(dynamic_top_name(settings.top)) + "+" +
                std::string(update_strategy_name(settings.update.strategy))),
          accel_(scene, settings) {}
    const std::string& name() const override { return name_; }
    double build_ms() const override { return accel_.build_ms(); }
    void update(AnimateFrameRow& row) override {
        const DynamicFrameReport report = accel_.update();
        row.update_ms = report.update_ms;
        row.top_ms = report.top_ms;
        row.sah = report.sah;
    }
    const Accel& accel() const override { return accel_.accel(); }

private:
    std::string name_;
    DynamicSceneAccel accel_;
};

double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

/// Closest hits of both ray sets, in parallel, timed. Embree's structures trace rays already
/// in Embree's layout (glue::EmbreeRayBatch, made before the timing), as `rebraid bench`
/// times them.
double time_render(const Accel& accel, const BenchRays& rays, std::vector<Hit>& hits) {
    std::vector<glue::EmbreeRayBatch> embree_rays;
    if (glue::EmbreeRayBatch::serves(accel)) {
        embree_rays.emplace_back(accel, rays.primary);
        embree_rays.emplace_back(accel, rays.diffuse);
    }
    const auto start = std::chrono::steady_clock::now();
    for (int s = 0; s < 2; ++s) {
        const std::vector<Ray>& set = s == 0 ? rays.primary : rays.diffuse;
        hits.resize(set.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), 64),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              if (!embree_rays.empty()) {
                                  embree_rays[s].intersect(range.begin(), range.end());
                                  return;
                              }
                              for (std::size_t i = range.begin(); i != range.end(); ++i)
                                  hits[i] = accel.intersect(set[i]);
                          });
    }
    return milliseconds_since(start);
}

std::vector<UpdateStrategy> chosen_strategies(const AnimateOptions& options) {
    // The library's list, so a new strategy is measured without touching this command.
    if (options.update_names.empty())
        return {std::begin(kUpdateStrategies), std::end(kUpdateStrategies)};
    std::vector<UpdateStrategy> strategies;
    for (const std::string& name : options.update_names) {
        try {
            strategies.push_back(parse_update_strategy(name));
        } catch (const Error& error) {
            throw Error("--update: " + std::string(error.what()));
        }
    }
    return strategies;
}

/// "rebuild, refit, ..., auto": every strategy's name, for the help text.
std::string strategy_names() {
    std::string names;
    for (UpdateStrategy strategy : kUpdateStrategies)
        names += (names.empty() ? "" : ", ") + std::string(update_strategy_name(strategy));
    return names;
}

std::vector<DynamicTop> chosen_tops(const AnimateOptions& options) {
    if (options.top_names.empty())
        return {DynamicTop::two_level, DynamicTop::rebraid, DynamicTop::rebraid_incremental};
    std::vector<DynamicTop> tops;
    for (const std::string& name : options.top_names) {
        try {
            tops.push_back(parse_dynamic_top(name));
        } catch (const Error& error) {
            throw Error("--top: " + std::string(error.what()));
        }
    }
    return tops;
}

void run_animate(const AnimateOptions& options) {
    // Everything cheap to check is checked before the scenes load.
    const std::vector<UpdateStrategy> strategies = chosen_strategies(options);
    const std::vector<DynamicTop> tops = chosen_tops(options);
    const DynamicPlacementSettings placement{.copy_count = options.copy_count,
                                             .size_fraction = options.size_fraction,
                                             .seed = options.seed};
    if (!(options.size_fraction > 0.0f))
        throw Error("--size must be more than 0: a copy needs some extent");
    placement.validate();
    RebraidSettings{.budget_factor = options.budget_factor}.validate();
    IncrementalTopSettings{.max_cut_pieces = options.max_cut_pieces}.validate();
    if (!(options.time_step >= 0.0f) || !std::isfinite(options.time_step))
        throw Error("--time-step " + std::to_string(options.time_step) + " must be >= 0");
    // Files and tools the end needs, so a long run is not lost at the last step.
    check_scene_file(options.static_path);
    if (!options.dynamic_path.empty()) check_scene_file(options.dynamic_path);
    check_output_file(options.csv_path, "CSV file");
    if (!options.plot_path.empty()) {
        check_plot_tools();
        check_output_file(options.plot_path, "plot");
    }

    const Scene static_scene = load_scene(options.static_path);
    std::unique_ptr<AnimatedObject> object;
    if (options.dynamic_path.empty()) {
        object = make_twisting_object();
    } else {
        load_scene(options.dynamic_path);  // the common messages for missing or wrong files
        object = load_gltf_animated_object(options.dynamic_path);
    }
    DynamicScene dynamic(static_scene, *object, placement);

    std::vector<std::unique_ptr<AnimateMethod>> methods;
    if (options.has_embree) {
        methods.push_back(std::make_unique<EmbreeMethod>(dynamic, glue::EmbreeDynamicMode::flat));
        methods.push_back(
            std::make_unique<EmbreeMethod>(dynamic, glue::EmbreeDynamicMode::flat_refit));
        methods.push_back(
            std::make_unique<EmbreeMethod>(dynamic, glue::EmbreeDynamicMode::instanced));
    }
    for (DynamicTop top : tops)
        for (UpdateStrategy strategy : strategies) {
            DynamicSceneAccelSettings settings;
            settings.top = top;
            settings.update.strategy = strategy;
            settings.rebraid.budget_factor = options.budget_factor;
            settings.incremental.max_cut_pieces = options.max_cut_pieces;
            if (options.static_builder != ObjectBuilderKind::own)
                settings.static_builder = make_object_builder(options.static_builder);
            methods.push_back(std::make_unique<OwnMethod>(dynamic, settings));
        }

    std::vector<AnimateMethodResult> results(methods.size());
    for (std::size_t m = 0; m < methods.size(); ++m) {
        results[m].method = methods[m]->name();
        results[m].build_ms = methods[m]->build_ms();
    }
    const Scene& scene = dynamic.scene();
    if (!options.is_json)
        std::cout << "animate: " << describe_scene(options.static_path) << " with "
                  << options.copy_count << " copies of "
                  << (options.dynamic_path.empty() ? std::string("the built-in twisting object")
                                                   : options.dynamic_path)
                  << ": " << scene.instanced_triangle_count() << " triangles ("
                  << dynamic.dynamic_meshes().size() << " dynamic meshes, "
                  << dynamic.moving_instances().size() << " moving instances); "
                  << options.frame_count << " frames of " << options.width << "x" << options.height
                  << " primary + diffuse rays\n";

    const BenchRaySettings ray_settings{
        .ray_count = static_cast<std::size_t>(options.width) * options.height,
        .aspect = static_cast<float>(options.width) / static_cast<float>(options.height),
        .seed = options.seed};
    viewer::ProgressBar progress("animate",
                                 static_cast<std::uint64_t>(options.frame_count) * methods.size());
    std::vector<Hit> hits;
    for (int frame = 0; frame < options.frame_count; ++frame) {
        AnimateFrameRow shared;
        shared.frame = frame;
        shared.time = static_cast<float>(frame) * options.time_step;
        const auto pose_start = std::chrono::steady_clock::now();
        dynamic.pose(shared.time);
        shared.animation_ms = milliseconds_since(pose_start);
        for (std::size_t m = 0; m < methods.size(); ++m) {
            AnimateFrameRow row = shared;
            methods[m]->update(row);
            results[m].frames.push_back(row);
        }
        // One ray set per frame, the same for every method: the camera frames this pose and
        // the bounces start where the first method's primary rays hit.
        BenchRaySettings frame_rays = ray_settings;
        frame_rays.seed = options.seed + static_cast<std::uint64_t>(frame);
        const BenchRays rays = make_bench_rays(scene, methods.front()->accel(), frame_rays);
        for (std::size_t m = 0; m < methods.size(); ++m) {
            results[m].frames.back().render_ms = time_render(methods[m]->accel(), rays, hits);
            progress.advance(1);
        }
    }
    progress.finish();

    if (!options.csv_path.empty())
        write_output(options.csv_path, [&](std::ostream& out) { write_animate_csv(out, results); });
    // The summary first: whatever happens to the plot, the measurements are not lost.
    if (options.is_json)
        std::cout << animate_summary_json(results).dump(2) << "\n";
    else
        print_animate_table(std::cout, results);
    std::cout.flush();
    if (!options.plot_path.empty()) {
        std::string csv = options.csv_path;
        std::filesystem::path temporary;
        if (csv.empty()) {
            temporary = std::filesystem::temp_directory_path() /
                        ("rebraid_animate_" + std::to_string(::getpid()) + ".csv");
            csv = temporary.string();
            write_output(csv, [&](std::ostream& out) { write_animate_csv(out, results); });
        }
        create_parent_directories(options.plot_path);
        try {
            plot_animate_csv(csv, options.plot_path);
        } catch (...) {
            if (!temporary.empty()) std::filesystem::remove(temporary);
            throw;
        }
        if (!temporary.empty()) std::filesystem::remove(temporary);
    }
}

}  // namespace

void add_animate_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<AnimateOptions>();
    CLI::App* command = app.add_subcommand(
        "animate",
        "Dynamic-in-static frame benchmark: copies of an animated glTF in a static scene; per "
        "frame, pose them, update every method's structure (Embree flat, flat with refit, "
        "instanced; twolevel, rebraid and rebraid-incremental tops, with each "
        "object-BVH update strategy) and "
        "render primary rays plus one diffuse bounce through it, all on the same rays.");
    command
        ->add_option("--static", options->static_path,
                     "static scene (.gltf/.glb; default: the built-in default scene)")
        ->type_name("S.glb");
    command
        ->add_option("--dynamic", options->dynamic_path,
                     "animated scene (.gltf/.glb; default: a built-in twisting object)")
        ->type_name("D.glb");
    command->add_option("--copies", options->copy_count, "copies of the animated scene")
        ->check(whole_number(1, 4096))
        ->capture_default_str()
        ->type_name("K");
    command->add_option("--frames", options->frame_count, "frames to run")
        ->check(whole_number(1, 1000000))
        ->capture_default_str()
        ->type_name("F");
    command->add_option("--time-step", options->time_step, "seconds of animation per frame")
        ->check(number_at_least(0))
        ->capture_default_str()
        ->type_name("DT");
    command
        ->add_option("--update", options->update_names,
                     "object-BVH update strategies, comma-separated: " + strategy_names() +
                         " (default: all)")
        ->delimiter(',')
        ->type_name("STRATEGY");
    command
        ->add_option("--top", options->top_names,
                     "top levels, comma-separated: twolevel, rebraid, rebraid-incremental (the "
                     "static instances' re-braided top built once, only the part around the "
                     "dynamic ones rebuilt per frame) (default: all three)")
        ->delimiter(',')
        ->type_name("TOP");
    command
        ->add_option("--budget-factor", options->budget_factor,
                     "extra BRefs per instance of the re-braided tops (paper: 4)")
        ->check(number_between(0, 1e6))
        ->capture_default_str()
        ->type_name("F");
    command
        ->add_option("--max-cut", options->max_cut_pieces,
                     "rebraid-incremental: most pieces of the static top each frame's upper "
                     "build takes")
        ->check(whole_number(1, NodeRef::kMaxFirst))
        ->capture_default_str()
        ->type_name("N");
    command->add_flag_callback(
        "--no-embree", [options] { options->has_embree = false; }, "leave out the Embree methods");
    add_object_builder_option(*command, "--static-builder", options->static_builder,
                              "BVHs of the static meshes in twolevel and rebraid methods (built "
                              "once)");
    command->add_option("--width", options->width, "image width of the rendered frame")
        ->check(whole_number(1, 32768))
        ->capture_default_str();
    command->add_option("--height", options->height, "image height of the rendered frame")
        ->check(whole_number(1, 32768))
        ->capture_default_str();
    command
        ->add_option("--size", options->size_fraction,
                     "largest extent of a copy over the static scene's largest extent (more "
                     "than 0, at most 1)")
        ->check(number_between(0, 1))
        ->capture_default_str()
        ->type_name("FRACTION");
    command->add_option("--seed", options->seed, "seed of the placement and the diffuse rays")
        ->check(whole_number(0, std::numeric_limits<std::int64_t>::max()))
        ->capture_default_str();
    command->add_flag("--json", options->is_json,
                      "print one JSON array: an object per method (method, mean_frame_ms, "
                      "max_frame_ms, mean_update_ms, mean_top_ms, mean_render_ms, final_sah, ...)");
    command
        ->add_option("--csv", options->csv_path,
                     "write one row per frame and method to this CSV file")
        ->type_name("FILE");
    command
        ->add_option("--plot", options->plot_path,
                     "plot frame times to this PNG (bench/plot_animate.py, /usr/bin/python3 "
                     "with matplotlib)")
        ->type_name("FILE.png");
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_animate(*options); }; });
}

}  // namespace rebraid::cli
