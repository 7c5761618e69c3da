#pragma once

#include <cstdint>
#include <memory>

#include "rebraid/core/animated_object.h"

namespace rebraid {

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
