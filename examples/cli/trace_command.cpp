// `rebraid trace [SCENE] RAYS`: closest hits of a ray file, one line per ray in input order.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "accel_factory.h"
#include "commands.h"
#include "option_checks.h"
#include "output_file.h"
#include "rebraid/core/error.h"
#include "rebraid/io/ray_file.h"
#include "scene_source.h"

namespace rebraid::cli {

namespace {

struct TraceOptions {
    /// One or two positionals: RAYS, or SCENE RAYS (see run_trace).
    std::vector<std::string> paths;
    std::string accel_name;
    AccelOptions accel_options;
    std::string hits_path;      ///< empty: standard output
    std::optional<float> time;  ///< --time: pose the glTF animation at this many seconds
};

/// CLI11 writes a positional taking one or two values as "NAME(1x)" in the usage line; the
/// name "[SCENE] RAYS" already says it all.
class TraceUsageFormatter : public CLI::Formatter {
public:
    std::string make_option_usage(const CLI::Option* option) const override {
        return make_option_name(option, true);
    }
};

/// Whether `path` ends in a scene file's extension (.gltf or .glb, any case).
bool has_scene_extension(const std::string& path) {
    std::string extension = std::filesystem::path(path).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return extension == ".gltf" || extension == ".glb";
}

void run_trace(const TraceOptions& options) {
    // SCENE is optional but comes first, so the positionals are taken as one list and the
    // last one is always the ray file.
    const std::string rays_path = options.paths.back();
    const std::string scene_path = options.paths.size() == 2 ? options.paths.front() : "";
    if (options.paths.size() == 1 && has_scene_extension(rays_path))
        throw Error("trace needs a ray file: 'rebraid trace [SCENE] RAYS', and '" + rays_path +
                    "' is a scene; write rays with 'rebraid rays " + rays_path +
                    " --count N -o RAYS'");

    // Everything that can fail is checked before the (slower) build.
    find_accel(options.accel_name);
    check_build_options_used(std::span(&options.accel_name, 1), options.accel_options);
    check_scene_file(scene_path);
    check_input_file(rays_path, "ray file");
    check_output_file(options.hits_path, "hit file");
    const std::vector<Ray> rays = read_ray_file(rays_path);
    const Scene scene =
        options.time ? load_scene_at_time(scene_path, *options.time) : load_scene(scene_path);
    const std::unique_ptr<Accel> accel =
        build_accel(options.accel_name, scene, options.accel_options);

    // Each ray writes its own slot, so the output order is the input order on any thread count.
    std::vector<Hit> hits(rays.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i != range.end(); ++i)
                              hits[i] = accel->intersect(rays[i]);
                      });

    write_output(options.hits_path, [&](std::ostream& out) { write_hits(out, hits); });
    const auto hit_count =
        std::count_if(hits.begin(), hits.end(), [](const Hit& hit) { return hit.is_hit(); });
    print_summary_on_terminal(
        "traced " + std::to_string(rays.size()) + " rays through " + options.accel_name + " in " +
        describe_scene(scene_path) + ": " + std::to_string(hit_count) + " hits" +
        (options.hits_path.empty() ? std::string() : ", written to " + options.hits_path));
}

}  // namespace

void add_trace_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<TraceOptions>();
    CLI::App* command = app.add_subcommand(
        "trace",
        "Trace a ray file and write the closest hit of every ray, one line per ray in input "
        "order: 't instID primID', or 'inf -1 -1' for a miss.");
    command
        ->add_option(
            "[SCENE] RAYS", options->paths,
            "an optional scene file (.gltf/.glb; the default scene when omitted or 'default'), "
            "then the ray file (one ray per line: ox oy oz dx dy dz tnear tfar)")
        ->expected(1, 2)
        ->required()
        ->type_name("");
    command->formatter(std::make_shared<TraceUsageFormatter>());
    add_accel_option(*command, options->accel_name);
    add_accel_build_options(*command, options->accel_options);
    command->add_option("-o,--output", options->hits_path, "hit file (default: standard output)")
        ->type_name("HITS");
    command
        ->add_option("--time", options->time,
                     "pose the scene at T seconds of its glTF animation (animation 0) first")
        ->check(finite_number())
        ->type_name("T");
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_trace(*options); }; });
}

}  // namespace rebraid::cli
