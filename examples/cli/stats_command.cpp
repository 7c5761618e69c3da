// `rebraid stats [SCENE]`: build a structure and report its size, build time and quality.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

#include "accel_factory.h"
#include "commands.h"
#include "scene_source.h"
#include "stats_json.h"

namespace rebraid::cli {

namespace {

struct StatsOptions {
    std::string scene_path;  ///< empty: the default scene
    std::string accel_name;
    AccelOptions accel_options;
    bool is_json = false;
};

void print_stats_text(std::ostream& out, const std::string& scene_name,
                      const std::string& accel_name, const AccelStats& stats) {
    constexpr int kKeyWidth = 16;
    out << std::left << std::setw(kKeyWidth) << "scene" << scene_name << "\n"
        << std::setw(kKeyWidth) << "accel" << accel_name << "\n";
    auto print_value = [&](std::string_view key, auto value) {
        out << std::setw(kKeyWidth) << key;
        if constexpr (std::is_floating_point_v<decltype(value)>)
            out << std::fixed << std::setprecision(key.ends_with("_ms") ? 3 : 6) << value
                << std::defaultfloat;
        else
            out << value;
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
    const Scene scene = load_scene(options.scene_path);
    const std::unique_ptr<Accel> accel = variant.entry->build(scene, variant.options);
    const AccelStats stats = accel->stats();
    if (options.is_json) {
        nlohmann::ordered_json json;
        json["scene"] = describe_scene(options.scene_path);
        json["accel"] = options.accel_name;
        if (variant.entry->has_object_bvhs)
            json["object_builder"] = object_builder_name(variant.options.object_builder);
        json.update(stats_to_json(stats));
        json["peak_rss_bytes"] = peak_rss_bytes();
        std::cout << json.dump(2) << "\n";
    } else {
        print_stats_text(std::cout, describe_scene(options.scene_path), options.accel_name, stats);
        std::cout << std::left << std::setw(16) << "peak_rss_bytes" << peak_rss_bytes() << "\n";
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
                      "accel and peak_rss_bytes: the process's peak resident memory)");
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_stats(*options); }; });
}

}  // namespace rebraid::cli
