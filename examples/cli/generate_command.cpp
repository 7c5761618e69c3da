// `rebraid generate KIND -o FILE.glb [--instances N] [--seed S] [--placement P]`: write a
// generated scene.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "option_checks.h"
#include "output_file.h"
#include "rebraid/core/error.h"
#include "rebraid/generators/scene_generators.h"
#include "rebraid/io/gltf_writer.h"
#include "status_line.h"

namespace rebraid::cli {

namespace {

struct GenerateOptions {
    std::string kind_name;
    std::string output_path;
    std::uint32_t instance_count = 0;  ///< 0: the kind's default
    std::uint64_t seed = 1;
    ObjectPlacement placement = ObjectPlacement::kind_default;
};

double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

void run_generate(const GenerateOptions& options) {
    const SceneKind kind = parse_scene_kind(options.kind_name);
    std::string extension = std::filesystem::path(options.output_path).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (extension != ".glb" && extension != ".gltf")
        throw Error("output file '" + options.output_path +
                    "' must end in .glb (one binary file) or .gltf (JSON plus a .bin file)");
    check_output_file(options.output_path, "scene file");
    StatusLine status;
    status.show("generate: making " + options.kind_name);
    const auto generate_start = std::chrono::steady_clock::now();
    Scene scene = generate_scene(kind, {.placement = options.placement,
                                        .instance_count = options.instance_count,
                                        .seed = options.seed});
    // Each mesh's instances together (in generation order), so every mesh's placements
    // become one EXT_mesh_gpu_instancing node: a million instances stay a small file.
    std::stable_sort(scene.instances.begin(), scene.instances.end(),
                     [](const Instance& a, const Instance& b) { return a.mesh_id < b.mesh_id; });
    const double generate_ms = milliseconds_since(generate_start);

    create_parent_directories(options.output_path);
    status.show("generate: writing " + options.output_path);
    const auto write_start = std::chrono::steady_clock::now();
    write_gltf_scene(scene, options.output_path, {.gpu_instancing = true});
    const double write_ms = milliseconds_since(write_start);
    status.clear();

    std::error_code error;
    const std::uintmax_t file_bytes = std::filesystem::file_size(options.output_path, error);
    std::cout << std::fixed << std::setprecision(1) << "kind " << scene_kind_name(kind) << "\n"
              << "seed " << options.seed << "\n"
              << "instances " << scene.instances.size() << "\n"
              << "meshes " << scene.meshes.size() << "\n"
              << "instanced_triangles " << scene.instanced_triangle_count() << "\n"
              << "mesh_triangles " << scene.mesh_triangle_count() << "\n"
              << "generate_ms " << generate_ms << "\n"
              << "write_ms " << write_ms << "\n"
              << "file " << options.output_path << "\n"
              << "file_bytes " << (error ? 0 : file_bytes) << "\n";
}

std::string kind_help() {
    std::string help = "scene family:";
    for (SceneKind kind : all_scene_kinds())
        help += std::string(kind == all_scene_kinds().front() ? " " : ", ") +
                std::string(scene_kind_name(kind)) + " (default " +
                std::to_string(default_instance_count(kind)) + " instances)";
    return help;
}

}  // namespace

void add_generate_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<GenerateOptions>();
    CLI::App* command = app.add_subcommand(
        "generate",
        "Write a generated scene as glTF (.glb or .gltf): trees, crown and powerplant overlap "
        "heavily, city hardly at all, huge has >= 10,000 instances and >= 100 M instanced "
        "triangles. The same kind, count and seed give the same file.");
    command->add_option("KIND", options->kind_name, kind_help())->required()->type_name("KIND");
    command->add_option("-o,--output", options->output_path, "glTF file to write (.glb/.gltf)")
        ->required()
        ->type_name("PATH");
    command
        ->add_option("--instances", options->instance_count,
                     "number of instances (0 = the kind's default)")
        ->check(whole_number(0, kMaxGeneratedInstances))
        ->capture_default_str();
    command->add_option("--seed", options->seed, "random seed")
        ->check(whole_number(0, std::numeric_limits<std::int64_t>::max()))
        ->capture_default_str();
    const std::map<std::string, ObjectPlacement> placements{
        {"kind", ObjectPlacement::kind_default},
        {"instanced", ObjectPlacement::instanced},
        {"world-space", ObjectPlacement::world_space}};
    command
        ->add_option("--placement", options->placement,
                     "kind: the family's own (world-space for crown and powerplant, as in the "
                     "paper; instanced for the rest); instanced: shared meshes placed by "
                     "transforms; world-space: every object its own mesh, identity transforms")
        ->transform(named_value(placements))
        ->default_str("kind");
    // Accepted like every subcommand's; generation itself is sequential.
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_generate(*options); }; });
}

}  // namespace rebraid::cli
