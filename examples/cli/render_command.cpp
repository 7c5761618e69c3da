// `rebraid render [SCENE]`: an auto-framed ambient-occlusion image of the scene, as a PNG.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <iostream>
#include <memory>
#include <string>

#include "accel_factory.h"
#include "commands.h"
#include "output_file.h"
#include "scene_source.h"
#include "viewer/camera.h"
#include "viewer/image_io.h"
#include "viewer/progress.h"
#include "viewer/renderer.h"

namespace rebraid::cli {

namespace {

struct RenderOptions {
    std::string scene_path;  ///< empty: the default scene
    std::string image_path = "out/render.png";
    std::string accel_name;
    AccelOptions accel_options;
    viewer::AoSettings ao;
};

double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

void run_render(const RenderOptions& options) {
    find_accel(options.accel_name);
    options.ao.validate();
    // Before the slow part, so a typo in the extension does not cost a whole render.
    viewer::check_image_format(options.image_path);
    const Scene scene = load_scene(options.scene_path);

    const auto build_start = std::chrono::steady_clock::now();
    const std::unique_ptr<Accel> accel =
        build_accel(options.accel_name, scene, options.accel_options);
    const double build_ms = milliseconds_since(build_start);

    const float aspect = static_cast<float>(options.ao.width) / options.ao.height;
    const viewer::Camera camera = viewer::frame_scene(scene, aspect);

    const auto render_start = std::chrono::steady_clock::now();
    viewer::ProgressBar progress("render", static_cast<std::uint64_t>(options.ao.height));
    const viewer::Image image =
        viewer::render_ao(scene, *accel, camera, options.ao,
                          [&progress](int row_count) { progress.advance(row_count); });
    progress.finish();
    const double render_ms = milliseconds_since(render_start);

    create_parent_directories(options.image_path);
    viewer::write_image(options.image_path, image);
    std::cout << "wrote " << options.image_path << ": " << image.width << "x" << image.height
              << ", " << options.ao.samples_per_pixel << " AO samples per pixel, "
              << describe_scene(options.scene_path) << ", " << options.accel_name << " (build "
              << static_cast<long>(build_ms) << " ms, render " << static_cast<long>(render_ms)
              << " ms)\n";
}

}  // namespace

void add_render_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* command = app.add_subcommand(
        "render",
        "Render the scene with ambient occlusion from an automatic camera (looking down at "
        "the whole scene) and write a PNG (or any format OpenImageIO writes, by extension).");
    command
        ->add_option("SCENE", options->scene_path,
                     "scene file (.gltf/.glb; the default scene when omitted)")
        ->type_name("PATH");
    command->add_option("-o,--output", options->image_path, "image file; folders are created")
        ->capture_default_str()
        ->type_name("IMAGE");
    command->add_option("--width", options->ao.width, "image width in pixels")
        ->check(CLI::Range(1, 32768))
        ->capture_default_str();
    command->add_option("--height", options->ao.height, "image height in pixels")
        ->check(CLI::Range(1, 32768))
        ->capture_default_str();
    command->add_option("--spp", options->ao.samples_per_pixel, "ambient-occlusion rays per pixel")
        ->check(CLI::Range(1, 65536))
        ->capture_default_str();
    command->add_option("--seed", options->ao.seed, "seed of the per-pixel samples")
        ->capture_default_str();
    add_accel_option(*command, options->accel_name);
    add_accel_build_options(*command, options->accel_options);
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_render(*options); }; });
}

}  // namespace rebraid::cli
