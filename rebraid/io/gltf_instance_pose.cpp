#include "rebraid/io/gltf_instance_pose.h"

#include <algorithm>
#include <cmath>

#include "rebraid/io/gltf_animation_math.h"

namespace rebraid {
namespace {

using gltf_animation::Vec3d;

/// Largest |cosine| between two columns that still counts as orthogonal: the columns of a
/// float rotation times scale are orthogonal to about float precision.
constexpr double kMaxColumnCosine = 1e-5;
/// Largest rebuild error of an entry, relative to the longest column.
constexpr double kMaxRebuildError = 1e-6;

Vec3d to_double(const Vec3f& v) {
    return {v.x, v.y, v.z};
}
double dot(const Vec3d& a, const Vec3d& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// Unit quaternion of the rotation matrix with columns `r` (Shepperd's method: divide by
/// the largest of the four candidate components, which is never small).
gltf_animation::Quatd quaternion_of(const std::array<Vec3d, 3>& r) {
    // r[c][row]: element (row, c).
    const double m00 = r[0][0], m11 = r[1][1], m22 = r[2][2];
    const double trace = m00 + m11 + m22;
    gltf_animation::Quatd q;
    if (trace >= std::max({m00, m11, m22})) {
        const double s = 2 * std::sqrt(1 + trace);
        q = {(r[1][2] - r[2][1]) / s, (r[2][0] - r[0][2]) / s, (r[0][1] - r[1][0]) / s, s / 4};
    } else if (m00 >= m11 && m00 >= m22) {
        const double s = 2 * std::sqrt(1 + m00 - m11 - m22);
        q = {s / 4, (r[1][0] + r[0][1]) / s, (r[2][0] + r[0][2]) / s, (r[1][2] - r[2][1]) / s};
    } else if (m11 >= m22) {
        const double s = 2 * std::sqrt(1 + m11 - m00 - m22);
        q = {(r[1][0] + r[0][1]) / s, s / 4, (r[2][1] + r[1][2]) / s, (r[2][0] - r[0][2]) / s};
    } else {
        const double s = 2 * std::sqrt(1 + m22 - m00 - m11);
        q = {(r[2][0] + r[0][2]) / s, (r[2][1] + r[1][2]) / s, s / 4, (r[0][1] - r[1][0]) / s};
    }
    return q.normalized();
}

}  // namespace

std::optional<GltfInstancePose> decompose_instance_transform(const AffineTransform& transform) {
    const std::array<Vec3d, 3> columns{to_double(transform.col_x), to_double(transform.col_y),
                                       to_double(transform.col_z)};
    Vec3d scale{};
    for (int c = 0; c < 3; ++c) scale[c] = std::sqrt(dot(columns[c], columns[c]));
    const double longest = std::max({scale[0], scale[1], scale[2]});
    if (!(scale[0] > 0 && scale[1] > 0 && scale[2] > 0) || !std::isfinite(longest))
        return std::nullopt;
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b)
            if (std::fabs(dot(columns[a], columns[b])) > kMaxColumnCosine * scale[a] * scale[b])
                return std::nullopt;
    if (transform.determinant() < 0) scale[0] = -scale[0];
    std::array<Vec3d, 3> rotation{};
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) rotation[c][row] = columns[c][row] / scale[c];
    const gltf_animation::Quatd q = quaternion_of(rotation);

    GltfInstancePose pose;
    pose.translation = {transform.translation.x, transform.translation.y, transform.translation.z};
    pose.rotation = {float(q.x), float(q.y), float(q.z), float(q.w)};
    pose.scale = {float(scale[0]), float(scale[1]), float(scale[2])};

    // Rebuild as the loader will, from the float values, and compare.
    gltf_animation::NodeTrs trs;
    trs.translation = {pose.translation[0], pose.translation[1], pose.translation[2]};
    trs.rotation = {pose.rotation[0], pose.rotation[1], pose.rotation[2], pose.rotation[3]};
    trs.scale = {pose.scale[0], pose.scale[1], pose.scale[2]};
    const gltf_animation::Affine3d rebuilt = gltf_animation::Affine3d::from_trs(trs);
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row)
            if (std::fabs(rebuilt.columns[c][row] - columns[c][row]) > kMaxRebuildError * longest)
                return std::nullopt;
    return pose;
}

}  // namespace rebraid
