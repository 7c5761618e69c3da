#pragma once

#include "rebraid/core/types.h"

namespace rebraid::viewer {

/// Linear [0, 1] to display values (sRGB transfer curve), clamped to [0, 1].
float linear_to_srgb(float linear);
Vec3f linear_to_srgb(Vec3f linear);

/// Display (sRGB-encoded) values in [0, 1] to linear.
float srgb_to_linear(float encoded);
Vec3f srgb_to_linear(Vec3f encoded);

/// The heatmap's colour ramp at `fraction` in [0, 1] (clamped): dark indigo for no work,
/// through blue, teal, green and amber, to red and nearly white for the most work. Display
/// (sRGB) values.
Vec3f heat_colour(float fraction);

}  // namespace rebraid::viewer
