#pragma once

// Turns a byte string into a small scene and rays that exercise the structures: random
// meshes (degenerate and coplanar triangles included), instances with shears, mirroring and
// non-uniform scales, one global scale from 2^-20 to 2^20. The libFuzzer target
// (fuzz_build_trace.cpp) feeds it the fuzzer's bytes; tests/top_level/randomized_scenes_test.cpp
// feeds it bytes from a seeded generator. Header-only so both build without an extra library.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/core/scene.h"
#include "rebraid/generators/random_rays.h"

namespace rebraid::fuzz {

/// Reads bytes in order; past the end it yields zeros, so every byte string decodes.
class ByteSource {
public:
    explicit ByteSource(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
    std::uint8_t u8() { return at_ < bytes_.size() ? bytes_[at_++] : 0; }
    std::uint32_t u32() {
        std::uint32_t value = 0;
        for (int i = 0; i < 4; ++i) value = value << 8u | u8();
        return value;
    }
    /// A signed byte scaled to [-1, 1].
    float unit() { return float(static_cast<std::int8_t>(u8())) / 127.0f; }

private:
    std::span<const std::uint8_t> bytes_;
    std::size_t at_ = 0;
};

/// Largest counts a decoded case has: small, so one case builds and traces in about a
/// millisecond and the fuzzer explores many.
struct FuzzedCaseLimits {
    std::uint32_t max_meshes = 3;
    std::uint32_t max_vertices = 16;
    std::uint32_t max_triangles = 24;
    std::uint32_t max_instances = 12;
    std::uint32_t random_rays = 32;
    std::uint32_t aimed_rays = 32;
};

/// A decoded scene and the rays to trace through it.
struct FuzzedCase {
    Scene scene;
    std::vector<Ray> rays;
};

/// A 3x4 transform from the bytes: a pure translation (half the instances), or a general
/// linear map (shear, mirror, non-uniform scale) plus translation. A linear map close to
/// singular relative to its size is replaced by the identity: rays mapped through its inverse
/// would lose most of their digits and no structure could be held to Embree's answer.
inline AffineTransform decode_transform(ByteSource& in, float scale) {
    AffineTransform xfm;
    const bool translation_only = (in.u8() & 1u) != 0;
    if (!translation_only) {
        xfm.col_x = Vec3f{in.unit(), in.unit(), in.unit()} * 4.0f;
        xfm.col_y = Vec3f{in.unit(), in.unit(), in.unit()} * 4.0f;
        xfm.col_z = Vec3f{in.unit(), in.unit(), in.unit()} * 4.0f;
        const float size = std::max({length(xfm.col_x), length(xfm.col_y), length(xfm.col_z)});
        if (!(size > 0.0f) || !(std::fabs(xfm.determinant()) >= 1e-2f * size * size * size))
            xfm = AffineTransform::identity();
    }
    xfm.translation = Vec3f{in.unit(), in.unit(), in.unit()} * (8.0f * scale);
    return xfm;
}

/// Decodes one case: any byte string gives a valid scene (Scene::validate()) and its rays.
inline FuzzedCase decode_case(std::span<const std::uint8_t> bytes,
                              const FuzzedCaseLimits& limits = {}) {
    ByteSource in(bytes);
    FuzzedCase result;
    Scene& scene = result.scene;
    // One global scale for everything: extreme magnitudes without mixing them in one scene
    // (a 2^-20 triangle beside 2^20 coordinates is below float precision for any structure).
    const float scale = std::ldexp(1.0f, int(in.u8() % 41) - 20);
    const std::uint32_t mesh_count = 1 + in.u8() % limits.max_meshes;
    for (std::uint32_t m = 0; m < mesh_count; ++m) {
        Mesh mesh;
        const std::uint32_t vertex_count = 3 + in.u8() % (limits.max_vertices - 2);
        const std::uint32_t triangle_count = 1 + in.u8() % limits.max_triangles;
        // Quantised corners: repeated and collinear vertices, coplanar triangles are common.
        for (std::uint32_t v = 0; v < vertex_count; ++v)
            mesh.positions.push_back(Vec3f{in.unit(), in.unit(), in.unit()} * scale);
        for (std::uint32_t t = 0; t < triangle_count; ++t)
            mesh.triangles.push_back(
                {in.u8() % vertex_count, in.u8() % vertex_count, in.u8() % vertex_count});
        scene.meshes.push_back(std::move(mesh));
    }
    const std::uint32_t instance_count = 1 + in.u8() % limits.max_instances;
    for (std::uint32_t i = 0; i < instance_count; ++i) {
        const MeshId mesh_id = in.u8() % mesh_count;
        scene.instances.push_back({mesh_id, decode_transform(in, scale)});
    }

    const BBox3f bounds = scene.bounds();
    result.rays = generate_random_rays(bounds, limits.random_rays, in.u32());
    // Rays aimed at triangle centroids, so hits are common even in sparse scenes.
    const float reach = length(bounds.extent()) + scale;
    for (std::uint32_t r = 0; r < limits.aimed_rays; ++r) {
        const InstanceId instance_id = in.u8() % instance_count;
        const Instance& instance = scene.instances[instance_id];
        const Mesh& mesh = scene.meshes[instance.mesh_id];
        const PrimId prim_id = in.u8() % mesh.triangles.size();
        const std::array<Vec3f, 3> corners = mesh.corners(prim_id);
        const Vec3f centroid = instance.object_to_world.transform_point(
            (corners[0] + corners[1] + corners[2]) * (1.0f / 3.0f));
        Vec3f dir{in.unit(), in.unit(), in.unit()};
        if (dir.x == 0.0f && dir.y == 0.0f && dir.z == 0.0f) dir = {0.0f, 0.0f, 1.0f};
        dir = dir * (1.0f / length(dir));
        result.rays.push_back({centroid - dir * reach, 0.0f, dir, INFINITY});
    }
    return result;
}

}  // namespace rebraid::fuzz
