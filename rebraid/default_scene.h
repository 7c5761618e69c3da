#pragma once

#include "rebraid/scene.h"

namespace rebraid {

/// The built-in scene every command uses when no file is given: several hundred instances
/// of a few generated meshes (thousands of triangles each) overlapping heavily, on a ground
/// mesh. Deterministic: no randomness outside a fixed seed.
Scene make_default_scene();

}  // namespace rebraid
