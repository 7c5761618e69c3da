// `rebraid render [SCENE]`: an image of the scene through any structure (ambient occlusion,
// path tracing, normals, or a traversal heatmap), optionally as an animation.
#include <CLI/CLI.hpp>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "accel_factory.h"
#include "commands.h"
#include "option_checks.h"
#include "output_file.h"
#include "rebraid/core/error.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/io/gltf_animation.h"
#include "rebraid/io/gltf_camera.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/render/camera_setup.h"
#include "rebraid/render/heatmap.h"
#include "rebraid/render/image_io.h"
#include "rebraid/render/interrupt.h"
#include "rebraid/render/progress.h"
#include "rebraid/render/renderer.h"
#include "rebraid/render/surface_materials.h"
#include "scene_source.h"

namespace rebraid::cli {

namespace {

constexpr const char* kHeatmapModeName = "heatmap";

struct RenderOptions {
    std::string scene_path;  ///< empty: the default scene
    std::string image_path = "out/render.png";
    std::string accel_name;
    AccelOptions accel_options;
    std::string mode_name = "ao";
    viewer::RenderSettings render;
    std::vector<std::string> compare_names;  ///< --compare: heatmaps of these, side by side
    std::string heat_metric_name = "total";
    int camera_id = -1;  ///< -1: the file's first camera, else auto-framing
    std::vector<float> look_from;
    std::vector<float> look_at;
    float fov_degrees = 0.0f;  ///< 0: keep the camera's
    int frame_count = 0;       ///< 0: one image, not numbered
    float time_step = 1.0f / 24.0f;
    int animation_id = 0;
    std::optional<float> start_time;  ///< --time: pose the animation at this time first
    std::set<std::string> given;      ///< the options on the command line ("--mode", ...)
};

/// The scene, and what its glTF file says beyond the geometry (empty for the default scene).
struct RenderScene {
    GltfLoadResult loaded;  ///< loaded.scene is the scene; model null for the default scene
    std::vector<GltfCamera> cameras;
    viewer::SurfaceMaterials materials;
    std::optional<GltfAnimator> animator;
};

double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

bool is_heatmap(const RenderOptions& options) {
    return options.mode_name == kHeatmapModeName || !options.compare_names.empty();
}

viewer::ShadingMode parse_mode(const std::string& name) {
    for (viewer::ShadingMode mode :
         {viewer::ShadingMode::ao, viewer::ShadingMode::path, viewer::ShadingMode::normals})
        if (viewer::shading_mode_name(mode) == name) return mode;
    throw Error("unknown --mode '" + name + "'; valid modes: ao, path, normals, heatmap");
}

viewer::HeatMetric parse_heat_metric(const std::string& name) {
    for (viewer::HeatMetric metric :
         {viewer::HeatMetric::total, viewer::HeatMetric::nodes, viewer::HeatMetric::triangles})
        if (viewer::heat_metric_name(metric) == name) return metric;
    throw Error("unknown --heat '" + name + "'; valid: total, nodes, triangles");
}

std::optional<Vec3f> point_option(const std::vector<float>& values, const char* name) {
    if (values.empty()) return std::nullopt;
    if (values.size() != 3)
        throw Error(std::string(name) + " needs three numbers X Y Z, got " +
                    std::to_string(values.size()));
    return Vec3f{values[0], values[1], values[2]};
}

/// The structures to render through: the --compare list, else --accel.
std::vector<std::string> structure_names(const RenderOptions& options) {
    return options.compare_names.empty() ? std::vector<std::string>{options.accel_name}
                                         : options.compare_names;
}

/// The animation option the user gave, for messages.
std::string animation_option(const RenderOptions& options) {
    return options.frame_count > 0 ? "--frames" : "--time";
}

RenderScene load_render_scene(const RenderOptions& options) {
    RenderScene result;
    if (is_default_scene(options.scene_path)) {
        if (options.frame_count > 0 || options.start_time)
            throw Error(animation_option(options) +
                        " plays a glTF animation; the default scene has no animation");
        result.loaded.scene = make_default_scene();
        result.loaded.scene.validate();
        return result;
    }
    // Bad paths get the message every command gives (load_scene() throws it); good ones are
    // loaded here, keeping the glTF document for cameras, materials and animation.
    std::error_code error;
    std::string extension = std::filesystem::path(options.scene_path).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!std::filesystem::is_regular_file(options.scene_path, error) ||
        (extension != ".gltf" && extension != ".glb"))
        load_scene(options.scene_path);
    result.loaded = load_gltf_scene_with_report(options.scene_path, {.keep_model = true});
    result.cameras = read_gltf_cameras(result.loaded);
    std::vector<std::string> warnings;
    result.materials =
        viewer::SurfaceMaterials::from_gltf(result.loaded, options.scene_path, warnings);
    for (const std::string& warning : warnings)
        std::cerr << "rebraid: warning: " << warning << "\n";
    if (options.frame_count > 0 || options.start_time) {
        result.animator.emplace(result.loaded,
                                GltfAnimationSettings{.animation = options.animation_id,
                                                      .file_label = options.scene_path});
        if (!result.animator->animated())
            throw Error(animation_option(options) + " plays a glTF animation; nothing in '" +
                        options.scene_path + "' is animated");
    }
    return result;
}

/// "out/anim.png" and frame 7 of 100 -> "out/anim_0007.png".
std::string numbered_path(const std::string& path, int frame, int frame_count) {
    const std::filesystem::path original(path);
    const int digits = std::max(4, static_cast<int>(std::to_string(frame_count - 1).size()));
    std::string number = std::to_string(frame);
    number.insert(
        0, static_cast<std::size_t>(std::max(0, digits - static_cast<int>(number.size()))), '0');
    std::filesystem::path numbered = original;
    numbered.replace_filename(original.stem().string() + "_" + number +
                              original.extension().string());
    return numbered.string();
}

/// One frame: the image, and a line saying what it shows.
struct FrameResult {
    viewer::Image image;
    bool is_complete = true;
    std::uint64_t rows_done = 0;  ///< over all panels
    std::uint64_t row_count = 0;
    std::string summary;
};

FrameResult render_frame(const RenderOptions& options, const Scene& scene,
                         const viewer::SurfaceMaterials& materials, const viewer::Camera& camera,
                         const viewer::RenderControl& control) {
    FrameResult frame;
    const std::vector<std::string> names = structure_names(options);
    frame.row_count = static_cast<std::uint64_t>(options.render.height) *
                      (is_heatmap(options) ? names.size() : 1);
    double build_ms = 0.0;
    if (is_heatmap(options)) {
        viewer::HeatmapSettings heat;
        heat.width = options.render.width;
        heat.height = options.render.height;
        heat.metric = parse_heat_metric(options.heat_metric_name);
        std::vector<viewer::HeatmapPanel> panels;
        for (const std::string& name : names) {
            const auto build_start = std::chrono::steady_clock::now();
            const std::unique_ptr<Accel> accel = build_accel(name, scene, options.accel_options);
            build_ms += milliseconds_since(build_start);
            panels.push_back(viewer::trace_heatmap(name, *accel, camera, heat, control));
            frame.rows_done += static_cast<std::uint64_t>(panels.back().rows_done);
            frame.is_complete = frame.is_complete && panels.back().rows_done == heat.height;
            if (!frame.is_complete) break;
        }
        // Panels an interrupt left out stay black, so the image keeps its size.
        for (std::size_t i = panels.size(); i < names.size(); ++i) {
            viewer::HeatmapPanel& empty = panels.emplace_back();
            empty.label = names[i];
            empty.width = heat.width;
            empty.height = heat.height;
            empty.per_pixel.assign(static_cast<std::size_t>(heat.width) * heat.height, {});
        }
        frame.image = viewer::draw_heatmaps(panels, heat);
        for (const viewer::HeatmapPanel& panel : panels)
            frame.summary += "  " + viewer::describe_heatmap_totals(panel) + "\n";
        frame.summary = "heatmap of " + std::string(viewer::heat_metric_name(heat.metric)) +
                        " work (build " + std::to_string(static_cast<long>(build_ms)) + " ms)\n" +
                        frame.summary;
        return frame;
    }
    const auto build_start = std::chrono::steady_clock::now();
    const std::unique_ptr<Accel> accel = build_accel(names[0], scene, options.accel_options);
    build_ms = milliseconds_since(build_start);
    const auto render_start = std::chrono::steady_clock::now();
    viewer::RenderResult result =
        viewer::render_image(scene, *accel, camera, materials, options.render, control);
    frame.image = std::move(result.image);
    frame.is_complete = result.is_complete();
    frame.rows_done = static_cast<std::uint64_t>(result.rows_done);
    const bool has_samples = options.render.mode != viewer::ShadingMode::normals;
    frame.summary = std::string(viewer::shading_mode_name(options.render.mode)) + ", " +
                    (has_samples ? std::to_string(options.render.samples_per_pixel) + " spp, "
                                 : std::string()) +
                    names[0] + " (build " + std::to_string(static_cast<long>(build_ms)) +
                    " ms, render " +
                    std::to_string(static_cast<long>(milliseconds_since(render_start))) + " ms)\n";
    return frame;
}

/// Refuses options the chosen mode would ignore, since the image would not show them.
void check_options_apply(const RenderOptions& options) {
    const auto given = [&](const char* name) { return options.given.contains(name); };
    const bool is_compare = !options.compare_names.empty();
    if (is_compare && given("--mode") && options.mode_name != kHeatmapModeName)
        throw Error("--compare draws heatmaps side by side, so --mode " + options.mode_name +
                    " does not apply; leave out --mode, or --compare to render one structure");
    if (is_compare && given("--accel"))
        throw Error(
            "--compare names the structures to draw, so --accel does not apply; list "
            "every structure in --compare");
    if (!is_heatmap(options) && given("--heat"))
        throw Error("--heat chooses what a heatmap shows; it needs --mode heatmap or --compare");
    if (given("--bounces") && (is_heatmap(options) || options.mode_name != "path"))
        throw Error("--bounces applies to --mode path only");
    if (given("--spp") && (is_heatmap(options) || options.mode_name == "normals"))
        throw Error("--spp applies to --mode ao and --mode path only");
    if (options.frame_count == 0 && given("--time-step"))
        throw Error("--time-step is the time between frames; it needs --frames");
    if (options.frame_count == 0 && !options.start_time && given("--animation"))
        throw Error("--animation chooses what --frames or --time plays; it needs one of them");
}

void run_render(RenderOptions options) {
    // Everything that can be checked before the slow part is checked first.
    const std::vector<std::string> names = structure_names(options);
    for (const std::string& name : names) find_accel(name);
    check_build_options_used(names, options.accel_options);
    std::vector<AccelVariant> variants;
    for (const std::string& name : names)
        variants.push_back(parse_accel_variant(name, options.accel_options));
    check_variants_differ(variants);
    check_options_apply(options);
    if (!is_heatmap(options)) options.render.mode = parse_mode(options.mode_name);
    parse_heat_metric(options.heat_metric_name);
    options.render.validate();
    if (options.frame_count > 0 && !(options.time_step >= 0.0f && std::isfinite(options.time_step)))
        throw Error("--time-step " + std::to_string(options.time_step) + " must be >= 0");
    viewer::check_image_format(options.image_path);
    check_scene_file(options.scene_path);
    check_output_file(options.frame_count > 0
                          ? numbered_path(options.image_path, 0, options.frame_count)
                          : options.image_path,
                      "output image");
    viewer::CameraRequest camera_request;
    if (options.camera_id >= 0) camera_request.gltf_camera_id = options.camera_id;
    camera_request.look_from = point_option(options.look_from, "--look-from");
    camera_request.look_at = point_option(options.look_at, "--look-at");
    if (options.fov_degrees != 0.0f) camera_request.fov_y_degrees = options.fov_degrees;

    RenderScene render_scene = load_render_scene(options);
    Scene& scene = render_scene.loaded.scene;
    const float start_time = options.start_time.value_or(0.0f);
    if (options.start_time && !std::isfinite(start_time))
        throw Error("--time " + std::to_string(start_time) + " is not a finite number of seconds");
    if (render_scene.animator) render_scene.animator->apply(start_time, scene);
    const float aspect = static_cast<float>(options.render.width) / options.render.height;
    // Chosen on the first frame's pose and kept, so an animation does not jump around.
    viewer::CameraChoice camera =
        viewer::choose_camera(scene, render_scene.cameras, camera_request, aspect);
    // A file's own camera may frame the model differently from what the user expects (it may
    // crop it): say how to pick another.
    const bool is_file_camera_by_default = !render_scene.cameras.empty() && options.camera_id < 0 &&
                                           options.look_from.empty() && options.look_at.empty() &&
                                           options.fov_degrees == 0.0f;
    if (is_file_camera_by_default)
        camera.description +=
            render_scene.cameras.size() == 1
                ? std::string(" (the file's own; --fov or --look-from X,Y,Z for another view)")
                : " (the first of the file's " + std::to_string(render_scene.cameras.size()) +
                      "; --camera N, --fov or --look-from X,Y,Z for another view)";

    const int frame_count = std::max(1, options.frame_count);
    const std::uint64_t rows_per_frame =
        static_cast<std::uint64_t>(options.render.height) * structure_names(options).size();
    viewer::InterruptGuard interrupt;
    // One bar per frame, finished before the frame's line goes to stdout.
    std::unique_ptr<viewer::ProgressBar> progress;
    const viewer::RenderControl control{
        .on_rows_done = [&progress](int row_count) { progress->advance(row_count); },
        .stop_requested = &interrupt.flag()};

    for (int frame_id = 0; frame_id < frame_count; ++frame_id) {
        const float time = start_time + static_cast<float>(frame_id) * options.time_step;
        if (render_scene.animator && frame_id > 0) render_scene.animator->apply(time, scene);
        progress = std::make_unique<viewer::ProgressBar>(
            options.frame_count > 0
                ? "frame " + std::to_string(frame_id + 1) + "/" + std::to_string(frame_count)
                : std::string("render"),
            rows_per_frame);
        const FrameResult frame =
            render_frame(options, scene, render_scene.materials, camera.camera, control);
        progress->finish();
        const std::string path = options.frame_count > 0
                                     ? numbered_path(options.image_path, frame_id, frame_count)
                                     : options.image_path;
        create_parent_directories(path);
        viewer::write_image(path, frame.image);
        if (!frame.is_complete || interrupt.is_interrupted())
            throw Error("interrupted (Ctrl-C): wrote the " + std::to_string(frame.rows_done) +
                        " of " + std::to_string(frame.row_count) + " rows rendered so far to " +
                        path);
        std::cout << "wrote " << path << ": " << frame.image.width << "x" << frame.image.height;
        if (options.frame_count > 0)
            std::cout << ", frame " << frame_id << " at t = " << time << " s";
        std::cout << ", " << describe_scene(options.scene_path) << ", " << camera.description
                  << ", " << frame.summary;
    }
}

}  // namespace

void add_render_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* command = app.add_subcommand(
        "render",
        "Render the scene to an image (PNG, or EXR when the name ends in .exr): ambient "
        "occlusion, diffuse path tracing, normals, or a heatmap of the traversal work. The "
        "camera is the file's first glTF camera, else one framing the whole scene from above.");
    command
        ->add_option("SCENE", options->scene_path,
                     "scene file (.gltf/.glb; the default scene when omitted or 'default')")
        ->type_name("PATH");
    command->add_option("-o,--output", options->image_path, "image file; folders are created")
        ->capture_default_str()
        ->type_name("IMAGE");
    command
        ->add_option("--mode", options->mode_name,
                     "ao (ambient occlusion), path (diffuse path tracing, glTF base colours and "
                     "textures), normals, heatmap (nodes visited + triangles tested per pixel)")
        ->check(one_of({"ao", "path", "normals", kHeatmapModeName}))
        ->capture_default_str();
    command->add_option("--width", options->render.width, "image width in pixels")
        ->check(whole_number(1, 32768))
        ->capture_default_str();
    command->add_option("--height", options->render.height, "image height in pixels")
        ->check(whole_number(1, 32768))
        ->capture_default_str();
    command
        ->add_option("--spp", options->render.samples_per_pixel,
                     "samples per pixel: ambient-occlusion rays (ao) or paths (path)")
        ->check(whole_number(1, 65536))
        ->capture_default_str();
    command
        ->add_option("--bounces", options->render.max_bounces,
                     "path: diffuse bounces after the first hit")
        ->check(whole_number(0, 64))
        ->capture_default_str();
    command->add_option("--seed", options->render.seed, "seed of the per-pixel samples")
        ->check(whole_number(0, std::numeric_limits<std::int64_t>::max()))
        ->capture_default_str();
    command
        ->add_option("--camera", options->camera_id,
                     "use glTF camera N (index in the file's cameras) instead of the first one")
        ->check(whole_number(0, 1 << 30))
        ->type_name("N");
    command
        ->add_option("--look-from", options->look_from,
                     "camera position X Y Z (or X,Y,Z); looks at --look-at or the scene centre")
        ->expected(3)
        ->delimiter(',')
        ->check(finite_number())
        ->type_name("X Y Z");
    command
        ->add_option("--look-at", options->look_at,
                     "point X Y Z (or X,Y,Z) the camera looks at; keeps the camera's position "
                     "unless --look-from is given")
        ->expected(3)
        ->delimiter(',')
        ->check(finite_number())
        ->type_name("X Y Z");
    command->add_option("--fov", options->fov_degrees, "vertical field of view in degrees")
        ->check(number_between(0.01, 179))
        ->type_name("DEGREES");
    command
        ->add_option("--compare", options->compare_names,
                     "heatmaps of these structures side by side in one image, with Mrays/s, "
                     "e.g. twolevel,rebraid")
        ->delimiter(',')
        ->type_name("A,B,...");
    command
        ->add_option("--heat", options->heat_metric_name,
                     "heatmap value: total (nodes + triangles), nodes or triangles")
        ->check(one_of({"total", "nodes", "triangles"}))
        ->capture_default_str();
    command
        ->add_option("--frames", options->frame_count,
                     "render F frames of the glTF animation to numbered images "
                     "(IMAGE_0000.png, ...)")
        ->check(whole_number(1, 1000000))
        ->type_name("F");
    command
        ->add_option("--time-step", options->time_step,
                     "seconds of animation between frames (with --frames)")
        ->check(number_at_least(0))
        ->capture_default_str()
        ->type_name("DT");
    command
        ->add_option("--time", options->start_time,
                     "pose the scene at T seconds of its glTF animation (the first frame's time "
                     "with --frames)")
        ->check(finite_number())
        ->type_name("T");
    command
        ->add_option("--animation", options->animation_id,
                     "glTF animation to play with --frames or --time (-1 = all at once)")
        ->check(whole_number(-1, 1 << 30))
        ->capture_default_str();
    add_accel_option(*command, options->accel_name);
    add_accel_build_options(*command, options->accel_options);
    add_common_options(*command, common);
    command->callback([options, command, &action] {
        for (const CLI::Option* option : command->get_options())
            if (option->count() > 0) options->given.insert(option->get_name());
        action = [options] { run_render(*options); };
    });
}

}  // namespace rebraid::cli
