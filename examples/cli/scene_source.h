#pragma once

#include <string>

#include "rebraid/core/scene.h"

namespace rebraid::cli {

/// The scene argument that names the built-in default scene, as an empty one does (a scene
/// file needs a .gltf or .glb extension, so no file is shadowed).
inline constexpr const char* kDefaultSceneName = "default";

/// Whether `path` names the built-in default scene: empty or kDefaultSceneName.
bool is_default_scene(const std::string& path);

/// Checks, without loading it, that `path` names the default scene or a readable .gltf or .glb
/// file; throws rebraid::Error naming the file and what is wrong otherwise. Commands call it
/// for every scene before any long work.
void check_scene_file(const std::string& path);

/// Loads the scene a command works on: the glTF file at `path` (.gltf or .glb), or the
/// built-in default scene when `path` is empty or "default". The result is validated. Throws
/// rebraid::Error naming the file when it is missing, has another extension or fails to load.
Scene load_scene(const std::string& path);

/// As load_scene(), then poses the scene at `time` seconds of its glTF animation number
/// `animation` (-1: all at once), as GltfAnimator::apply does: skinned and morphed meshes
/// deformed, animated nodes moved. Throws rebraid::Error naming the file for bad animation
/// data, a non-finite time, or a scene without animation (the default scene, or a file in
/// which nothing moves), where the time would change nothing.
Scene load_scene_at_time(const std::string& path, float time, int animation = 0);

/// How messages name the scene: the path, or "default scene".
std::string describe_scene(const std::string& path);

}  // namespace rebraid::cli
