#include "scene_source.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "rebraid/default_scene.h"
#include "rebraid/error.h"
#include "rebraid/gltf_scene.h"

namespace rebraid::cli {

namespace {

std::string lowercase_extension(const std::filesystem::path& path) {
    std::string extension = path.extension().string();
    std::ranges::transform(extension, extension.begin(),
                           [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return extension;
}

}  // namespace

Scene load_scene(const std::string& path) {
    if (path.empty()) {
        Scene scene = make_default_scene();
        scene.validate();
        return scene;
    }
    // Checked here so the message is the same for every loader and names the user's path.
    std::error_code error;
    if (!std::filesystem::exists(path, error))
        throw Error("scene file '" + path + "' does not exist");
    if (std::filesystem::is_directory(path, error))
        throw Error("scene file '" + path + "' is a directory");
    const std::string extension = lowercase_extension(path);
    if (extension != ".gltf" && extension != ".glb")
        throw Error("scene file '" + path + "' is not a .gltf or .glb file");
    Scene scene = load_gltf_scene(path);
    scene.validate();
    return scene;
}

std::string describe_scene(const std::string& path) {
    return path.empty() ? std::string("default scene") : path;
}

}  // namespace rebraid::cli
