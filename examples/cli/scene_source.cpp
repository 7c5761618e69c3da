#include "scene_source.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "output_file.h"
#include "rebraid/core/error.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/io/gltf_animation.h"
#include "rebraid/io/gltf_scene.h"

namespace rebraid::cli {

namespace {

std::string lowercase_extension(const std::filesystem::path& path) {
    std::string extension = path.extension().string();
    std::ranges::transform(extension, extension.begin(),
                           [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return extension;
}

}  // namespace

bool is_default_scene(const std::string& path) {
    return path.empty() || path == kDefaultSceneName;
}

void check_scene_file(const std::string& path) {
    if (is_default_scene(path)) return;
    // Checked here so the message is the same for every loader and names the user's path.
    check_input_file(path, "scene file");
    const std::string extension = lowercase_extension(path);
    if (extension != ".gltf" && extension != ".glb")
        throw Error("scene file '" + path + "' is not a .gltf or .glb file");
}

Scene load_scene(const std::string& path) {
    if (is_default_scene(path)) {
        Scene scene = make_default_scene();
        scene.validate();
        return scene;
    }
    check_scene_file(path);
    Scene scene = load_gltf_scene(path);
    scene.validate();
    return scene;
}

Scene load_scene_at_time(const std::string& path, float time, int animation) {
    if (!std::isfinite(time))
        throw Error("--time " + std::to_string(time) + " is not a finite number of seconds");
    // A time on a scene that does not move would be accepted and change nothing.
    if (is_default_scene(path))
        throw Error("--time poses an animated glTF scene; the default scene has no animation");
    check_scene_file(path);
    GltfLoadResult loaded = load_gltf_scene_with_report(path, {.keep_model = true});
    const GltfAnimator animator(loaded,
                                GltfAnimationSettings{.animation = animation, .file_label = path});
    if (!animator.animated())
        throw Error("--time poses an animated glTF scene; nothing in '" + path + "' is animated");
    animator.apply(time, loaded.scene);
    loaded.scene.validate();
    return std::move(loaded.scene);
}

std::string describe_scene(const std::string& path) {
    return is_default_scene(path) ? std::string("default scene") : path;
}

}  // namespace rebraid::cli
