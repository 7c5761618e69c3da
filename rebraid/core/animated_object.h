#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/core/scene.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// Something that moves over time and can be placed in a static scene: a glTF animation
/// (rebraid/io/gltf_dynamic_object.h) or the built-in twisting tube
/// (rebraid/generators/twisting_object.h). Its scene has a
/// fixed layout (meshes and instances never change in number); pose() rewrites positions of
/// deformed_meshes() and transforms of moving_instances() in place.
class AnimatedObject {
public:
    virtual ~AnimatedObject() = default;

    /// The object's scene in the layout pose() expects, posed at time 0.
    virtual const Scene& rest_scene() const = 0;
    /// Seconds of one loop of the animation (> 0 when anything moves).
    virtual float duration() const = 0;
    /// Poses `scene` (a copy of rest_scene(), possibly posed before) at `time` seconds.
    /// Thread-safe for distinct scenes.
    virtual void pose(float time, Scene& scene) const = 0;
    /// Meshes whose positions change over time (ascending).
    virtual const std::vector<MeshId>& deformed_meshes() const = 0;
    /// Instances whose transform changes over time (ascending).
    virtual const std::vector<InstanceId>& moving_instances() const = 0;
};

}  // namespace rebraid
