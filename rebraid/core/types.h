#pragma once

#include <cmath>
#include <cstdint>

namespace rebraid {

using MeshId = std::uint32_t;      ///< index into Scene::meshes
using InstanceId = std::uint32_t;  ///< index into Scene::instances (glTF depth-first order)
using PrimId = std::uint32_t;      ///< triangle index within its mesh

/// Marks "no hit" in instance and primitive ids (printed as -1 in hit files).
inline constexpr std::uint32_t kInvalidId = 0xffffffffu;

/// Three floats; the only vector type of the core. Plain aggregate so arrays of it can be
/// handed to Embree and glTF buffers without conversion.
struct Vec3f {
    float x = 0.0f, y = 0.0f, z = 0.0f;

    float operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
    float& operator[](int axis) { return axis == 0 ? x : (axis == 1 ? y : z); }
    friend bool operator==(const Vec3f&, const Vec3f&) = default;
};

inline Vec3f operator+(Vec3f a, Vec3f b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3f operator-(Vec3f a, Vec3f b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3f operator-(Vec3f a) { return {-a.x, -a.y, -a.z}; }
inline Vec3f operator*(Vec3f a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3f operator*(float s, Vec3f a) { return a * s; }
inline Vec3f operator*(Vec3f a, Vec3f b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline Vec3f operator/(Vec3f a, float s) { return {a.x / s, a.y / s, a.z / s}; }
inline float dot(Vec3f a, Vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3f cross(Vec3f a, Vec3f b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3f a) { return std::sqrt(dot(a, a)); }
inline Vec3f normalize(Vec3f a) { return a / length(a); }
// Plain comparisons rather than std::fmin/fmax: they compile to single min/max instructions
// (the libm calls dominated build profiles). Inputs are never NaN: scenes are validated.
inline float min(float a, float b) { return b < a ? b : a; }
inline float max(float a, float b) { return a < b ? b : a; }
inline Vec3f min(Vec3f a, Vec3f b) { return {min(a.x, b.x), min(a.y, b.y), min(a.z, b.z)}; }
inline Vec3f max(Vec3f a, Vec3f b) { return {max(a.x, b.x), max(a.y, b.y), max(a.z, b.z)}; }
inline bool is_finite(Vec3f a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

}  // namespace rebraid
