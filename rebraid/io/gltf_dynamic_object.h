#pragma once

#include <memory>
#include <string>

#include "rebraid/core/animated_object.h"
#include "rebraid/io/gltf_animation.h"

namespace rebraid {

/// A glTF file's animation as an AnimatedObject (for DynamicScene): the file loaded with its
/// model kept, posed by a GltfAnimator with GltfHiddenPose::collapsed_mesh (whatever
/// `settings` say), so the layout stays fixed when a pose hides an instance. Throws
/// rebraid::Error naming the file when it cannot be loaded, has bad animation data, or
/// nothing in it moves.
std::unique_ptr<AnimatedObject> load_gltf_animated_object(
    const std::string& path, const GltfAnimationSettings& settings = {});

}  // namespace rebraid
