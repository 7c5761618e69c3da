// `rebraid rays [SCENE] --count N`: a reproducible ray file of random rays around the scene.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "option_checks.h"
#include "output_file.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/io/ray_file.h"
#include "scene_source.h"

namespace rebraid::cli {

namespace {

/// The most rays one file holds (32 bytes each in memory, 2 GiB in all).
constexpr std::int64_t kMaxRayCount = std::int64_t{1} << 26;

struct RaysOptions {
    std::string scene_path;  ///< empty: the default scene
    std::size_t count = 0;
    std::uint64_t seed = 1;
    std::string rays_path;  ///< empty: standard output
};

void run_rays(const RaysOptions& options) {
    check_scene_file(options.scene_path);
    check_output_file(options.rays_path, "ray file");
    const Scene scene = load_scene(options.scene_path);
    const std::vector<Ray> rays = generate_random_rays(scene.bounds(), options.count, options.seed);
    write_output(options.rays_path, [&](std::ostream& out) { write_rays(out, rays); });
    if (!options.rays_path.empty())
        print_summary_on_terminal("wrote " + std::to_string(rays.size()) + " rays around the " +
                                  describe_scene(options.scene_path) + " to " + options.rays_path);
}

}  // namespace

void add_rays_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<RaysOptions>();
    CLI::App* command = app.add_subcommand(
        "rays",
        "Write a ray file of random rays: origins in and around the scene bounds, directions "
        "uniform on the sphere; the same seed gives the same file.");
    command
        ->add_option("SCENE", options->scene_path,
                     "scene file (.gltf/.glb; the default scene when omitted or 'default')")
        ->type_name("PATH");
    command->add_option("-n,--count", options->count, "number of rays")
        ->check(whole_number(1, kMaxRayCount))
        ->required()
        ->type_name("N");
    command->add_option("-o,--output", options->rays_path, "ray file (default: standard output)")
        ->type_name("RAYS");
    command->add_option("--seed", options->seed, "random seed")
        ->check(whole_number(0, std::numeric_limits<std::int64_t>::max()))
        ->capture_default_str();
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_rays(*options); }; });
}

}  // namespace rebraid::cli
