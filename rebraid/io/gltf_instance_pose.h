#pragma once

#include <array>
#include <optional>

#include "rebraid/core/transform.h"

namespace rebraid {

/// An instance transform as glTF's TRS properties hold it: translation, unit rotation
/// quaternion (x, y, z, w) and per-axis scale, in float; the transform is T * R * S.
struct GltfInstancePose {
    std::array<float, 3> translation{};
    std::array<float, 4> rotation{0, 0, 0, 1};
    std::array<float, 3> scale{1, 1, 1};
};

/// `transform` as T * R * S, or nothing when it has no such form: its columns are not
/// orthogonal (a shear), or the float T, R, S rebuild it (in double, as the loader does)
/// with an entry off by more than 1e-6 of the largest column length. A mirroring
/// transform (negative determinant) gets a negative x scale.
std::optional<GltfInstancePose> decompose_instance_transform(const AffineTransform& transform);

}  // namespace rebraid
