#include "rebraid/render/shading.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace rebraid::viewer {

namespace {

/// Two unit vectors perpendicular to the unit `n` and to each other (Frisvad's construction
/// with the sign fix of Duff et al., which has no singularity at n.z = -1).
void orthonormal_basis(Vec3f n, Vec3f& tangent, Vec3f& bitangent) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    tangent = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    bitangent = {b, sign + n.y * n.y * a, -n.y};
}

/// Hue in [0, 1) to an RGB colour of the given saturation and value.
Vec3f hsv_to_rgb(float hue, float saturation, float value) {
    auto channel = [&](float offset) {
        const float k = std::fmod(offset + hue * 6.0f, 6.0f);
        const float ramp = std::clamp(std::min(k, 4.0f - k), 0.0f, 1.0f);
        return value * (1.0f - saturation * ramp);
    };
    return {channel(5.0f), channel(3.0f), channel(1.0f)};
}

std::uint32_t hash_u32(std::uint32_t x) {
    // A 32-bit integer finaliser: every input bit affects every output bit.
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

}  // namespace

Vec3f world_geometric_normal(const Scene& scene, InstanceId instance_id, PrimId prim_id) {
    const Instance& instance = scene.instances[instance_id];
    const auto corners = scene.meshes[instance.mesh_id].corners(prim_id);
    const AffineTransform& to_world = instance.object_to_world;
    const Vec3f p0 = to_world.transform_point(corners[0]);
    const Vec3f p1 = to_world.transform_point(corners[1]);
    const Vec3f p2 = to_world.transform_point(corners[2]);
    const Vec3f n = cross(p1 - p0, p2 - p0);
    const float n_length = length(n);
    return n_length > 0.0f ? n / n_length : Vec3f{};
}

Vec3f instance_tint(InstanceId instance_id) {
    const std::uint32_t hash = hash_u32(instance_id * 0x9e3779b9u + 0x632be5abu);
    const float hue = static_cast<float>(hash & 0xffffu) / 65536.0f;
    const float saturation = 0.25f + 0.2f * static_cast<float>((hash >> 16u) & 0xffu) / 255.0f;
    const float value = 0.8f + 0.15f * static_cast<float>(hash >> 24u) / 255.0f;
    return hsv_to_rgb(hue, saturation, value);
}

Vec3f sky_colour(Vec3f direction, Vec3f world_up) {
    const float height = std::clamp(dot(direction, world_up), -1.0f, 1.0f);
    const Vec3f horizon{0.90f, 0.93f, 0.97f};
    const Vec3f zenith{0.32f, 0.52f, 0.85f};
    const Vec3f below{0.56f, 0.65f, 0.78f};  // a hazy blue, so views from above look airy
    if (height < 0.0f) return horizon + (below - horizon) * std::sqrt(-height);
    return horizon + (zenith - horizon) * std::sqrt(height);
}

Vec3f sample_cosine_hemisphere(Vec3f normal, float u1, float u2) {
    // Uniform on the unit disc, lifted onto the hemisphere (Malley's method).
    const float radius = std::sqrt(u1);
    const float angle = 2.0f * std::numbers::pi_v<float> * u2;
    const float height = std::sqrt(std::max(0.0f, 1.0f - u1));
    Vec3f tangent, bitangent;
    orthonormal_basis(normal, tangent, bitangent);
    return tangent * (radius * std::cos(angle)) + bitangent * (radius * std::sin(angle)) +
           normal * height;
}

}  // namespace rebraid::viewer
