#pragma once

#include "rebraid/core/scene.h"

namespace rebraid {

/// The built-in scene every command uses when no file is given: several hundred instances
/// of a few generated meshes (thousands of triangles each) overlapping heavily, on a ground
/// mesh. Deterministic: no randomness outside a fixed seed.
Scene make_default_scene();

}  // namespace rebraid
