#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "rebraid/scene.h"
#include "rebraid/types.h"

namespace rebraid {

/// Something that moves over time and can be placed in a static scene: a glTF animation
/// (rebraid/gltf_dynamic_object.h) or the built-in procedural object below. Its scene has a
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

/// The built-in animated object: a tube (a torus knot stretched along +Y) that twists about
/// its axis and sways sideways, a deformation that stretches some triangles and swaps the
/// neighbourhoods of others, as a skinned character does. One mesh, one instance.
struct TwistingObjectSettings {
    std::uint32_t path_segment_count = 512;  ///< along the knot; triangles = 2 * this * tube
    std::uint32_t tube_segment_count = 16;   ///< around the tube
    float twist_turns = 0.75f;               ///< largest twist from bottom to top, in turns
    float sway = 0.6f;                       ///< largest sideways bend at the top, in radii
    float period = 2.0f;                     ///< seconds of one loop
};

/// Makes the built-in animated object. Throws rebraid::Error for a period <= 0.
std::unique_ptr<AnimatedObject> make_twisting_object(const TwistingObjectSettings& settings = {});

}  // namespace rebraid
