#pragma once

#include <string>

#include "rebraid/scene.h"

namespace rebraid::cli {

/// Loads the scene a command works on: the glTF file at `path` (.gltf or .glb), or the
/// built-in default scene when `path` is empty. The result is validated. Throws
/// rebraid::Error naming the file when it is missing, has another extension or fails to load.
Scene load_scene(const std::string& path);

/// How messages name the scene: the path, or "default scene".
std::string describe_scene(const std::string& path);

}  // namespace rebraid::cli
