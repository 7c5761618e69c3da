// `rebraid stats [SCENE]`: build a structure and report its size, build time and quality.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>

#include "accel_factory.h"
#include "commands.h"
#include "rebraid/core/build_timer.h"
#include "scene_source.h"
#include "stats_json.h"
#include "status_line.h"

namespace rebraid::cli {

namespace {

struct StatsOptions {
    std::string scene_path;  ///< empty: the default scene
    std::string accel_name;
    AccelOptions accel_options;
    bool is_json = false;
};

/// What a value means where its name alone does not say, printed after it.
std::string_view stats_field_note(std::string_view key) {
    if (key == "sah") return "SAH cost of the whole structure (docs/design.md)";
    if (key == "brefs") return "top-level references: one per instance, plus those opening added";
    if (key == "budget") return "extra BRefs opening may add beyond one per instance";
    if (key == "opened") return "BRefs opened into their children";
    if (key == "mesh_copies")
        return "world-space copies of meshes several instances place (world-copies)";
    if (key == "kernels") return "instruction set of the traversal (REBRAID_SIMD chooses)";
    if (key == "triangle_test")
        return "ray-triangle test of the traversal: moller (Embree's default) or watertight "
               "(robust=1)";
    return {};
}

void print_stats_text(std::ostream& out, const std::string& scene_name,
                      const std::string& accel_name, const AccelStats& stats) {
    constexpr int kKeyWidth = 16;
    constexpr int kValueWidth = 22;
    out << std::left << std::setw(kKeyWidth) << "scene" << scene_name << "\n"
        << std::setw(kKeyWidth) << "accel" << accel_name << "\n";
    auto print_value = [&](std::string_view key, auto value) {
        std::ostringstream text;
        if constexpr (std::is_floating_point_v<decltype(value)>)
            text << std::fixed << std::setprecision(key.ends_with("_ms") ? 3 : 6) << value;
        else
            text << value;
        out << std::setw(kKeyWidth) << key;
        const std::string_view note = stats_field_note(key);
        if (note.empty())
            out << text.str();
        else
            out << std::setw(kValueWidth) << text.str() << note;
        out << "\n";
    };
    for_each_stats_field(stats, [&](std::string_view key, const auto& value) {
        if constexpr (IsOptional<std::decay_t<decltype(value)>>::value) {
            if (value) print_value(key, *value);
        } else {
            print_value(key, value);
        }
    });
}

void run_stats(const StatsOptions& options) {
    // The variant's own options (a NAME:KEY=VALUE suffix overrides the command line's), so the
    // JSON names the object builder that actually built the structure.
    options.accel_options.rebraid.validate();
    check_build_options_used(std::span(&options.accel_name, 1), options.accel_options);
    const AccelVariant variant = parse_accel_variant(options.accel_name, options.accel_options);
    check_scene_file(options.scene_path);
    StatusLine status;
    status.show("stats: loading " + describe_scene(options.scene_path));
    const BuildTimer load_timer;
    const Scene scene = load_scene(options.scene_path);
    const double load_ms = load_timer.elapsed_ms();
    status.show("stats: building " + options.accel_name);
    const std::unique_ptr<Accel> accel = variant.entry->build(scene, variant.options);
    const AccelStats stats = accel->stats();
    status.clear();
    if (options.is_json) {
        nlohmann::ordered_json json;
        json["scene"] = describe_scene(options.scene_path);
        json["accel"] = options.accel_name;
        if (variant.entry->has_object_bvhs)
            json["object_builder"] = object_builder_name(variant.options.object_builder);
        json["load_ms"] = load_ms;
        json.update(stats_to_json(stats));
        json["peak_rss_bytes"] = peak_rss_bytes();
        std::cout << json.dump(2) << "\n";
    } else {
        print_stats_text(std::cout, describe_scene(options.scene_path), options.accel_name, stats);
        std::cout << std::left << std::setw(16) << "load_ms" << std::fixed << std::setprecision(3)
                  << load_ms << "\n"
                  << std::setw(16) << "peak_rss_bytes" << peak_rss_bytes() << "\n";
        if (!stats.sah)
            std::cout << "(no sah, nodes or leaves: " << options.accel_name
                      << " is Embree's own BVH, which Embree does not let others inspect)\n";
    }
}

}  // namespace

void add_stats_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<StatsOptions>();
    CLI::App* command = app.add_subcommand(
        "stats",
        "Build a structure and print its triangles, instances, meshes, build time and "
        "every statistic it reports.");
    command
        ->add_option("SCENE", options->scene_path,
                     "scene file (.gltf/.glb; the default scene when omitted or 'default')")
        ->type_name("PATH");
    add_accel_option(*command, options->accel_name);
    add_accel_build_options(*command, options->accel_options);
    command->add_flag("--json", options->is_json,
                      "print one JSON object (keys as the AccelStats fields, plus scene, "
                      "accel, load_ms: the time reading the scene file took, and "
                      "peak_rss_bytes: the process's peak resident memory)");
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_stats(*options); }; });
}

}  // namespace rebraid::cli
