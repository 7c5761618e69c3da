#pragma once

// Double-precision node math of the glTF animator (internal to rebraid::io): TRS poses,
// quaternions and affine maps. Node chains are composed in double, like the loader does, and
// converted to float once per instance or joint.

#include <array>
#include <cmath>

#include "rebraid/core/transform.h"

namespace rebraid::gltf_animation {

using Vec3d = std::array<double, 3>;

/// Unit quaternion (x, y, z, w), the glTF component order.
struct Quatd {
    double x = 0, y = 0, z = 0, w = 1;

    double dot(const Quatd& o) const { return x * o.x + y * o.y + z * o.z + w * o.w; }
    /// This quaternion scaled to unit length; the identity for a zero quaternion.
    Quatd normalized() const {
        const double length = std::sqrt(dot(*this));
        if (!(length > 0)) return {};
        return {x / length, y / length, z / length, w / length};
    }
};

/// Spherical linear interpolation from `a` (s = 0) to `b` (s = 1) along the shorter arc
/// (glTF 2.0 specification, appendix "Interpolation": q and -q are the same rotation).
inline Quatd slerp(const Quatd& a, Quatd b, double s) {
    double cosine = a.dot(b);
    if (cosine < 0) {
        b = {-b.x, -b.y, -b.z, -b.w};
        cosine = -cosine;
    }
    double weight_a = 1 - s, weight_b = s;
    // Nearly equal rotations: sin(angle) ~ 0, the linear blend is exact to double precision.
    if (cosine < 1 - 1e-9) {
        const double angle = std::acos(cosine);
        const double inverse_sine = 1 / std::sin(angle);
        weight_a = std::sin((1 - s) * angle) * inverse_sine;
        weight_b = std::sin(s * angle) * inverse_sine;
    }
    return Quatd{weight_a * a.x + weight_b * b.x, weight_a * a.y + weight_b * b.y,
                 weight_a * a.z + weight_b * b.z, weight_a * a.w + weight_b * b.w}
        .normalized();
}

/// A node's local pose as glTF stores it: M = T * R * S.
struct NodeTrs {
    Vec3d translation{0, 0, 0};
    Quatd rotation;
    Vec3d scale{1, 1, 1};
};

/// 3x4 affine map in double. Columns: x, y, z, translation.
struct Affine3d {
    std::array<Vec3d, 4> columns{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}}};

    Vec3d apply_linear(const Vec3d& v) const {
        Vec3d out{};
        for (int row = 0; row < 3; ++row)
            out[row] = columns[0][row] * v[0] + columns[1][row] * v[1] + columns[2][row] * v[2];
        return out;
    }
    /// this * other: first `other`, then this.
    Affine3d operator*(const Affine3d& other) const {
        Affine3d out;
        for (int c = 0; c < 3; ++c) out.columns[c] = apply_linear(other.columns[c]);
        out.columns[3] = apply_linear(other.columns[3]);
        for (int row = 0; row < 3; ++row) out.columns[3][row] += columns[3][row];
        return out;
    }
    /// Column-major 4x4 (16 numbers, bottom row ignored), the layout of glTF matrices.
    template <typename Number>
    static Affine3d from_column_major(const Number* m) {
        Affine3d out;
        for (int c = 0; c < 4; ++c)
            out.columns[c] = {double(m[4 * c]), double(m[4 * c + 1]), double(m[4 * c + 2])};
        return out;
    }
    static Affine3d from_trs(const NodeTrs& pose) {
        const Quatd q = pose.rotation.normalized();
        const double x = q.x, y = q.y, z = q.z, w = q.w;
        // Columns of the rotation matrix of q, each scaled by its axis' scale factor.
        const std::array<Vec3d, 3> rotation{{
            {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)},
            {2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)},
            {2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)},
        }};
        Affine3d out;
        for (int c = 0; c < 3; ++c)
            for (int row = 0; row < 3; ++row)
                out.columns[c][row] = rotation[c][row] * pose.scale[c];
        out.columns[3] = pose.translation;
        return out;
    }
    AffineTransform to_float() const {
        auto vec = [](const Vec3d& c) { return Vec3f{float(c[0]), float(c[1]), float(c[2])}; };
        return {vec(columns[0]), vec(columns[1]), vec(columns[2]), vec(columns[3])};
    }
};

}  // namespace rebraid::gltf_animation
