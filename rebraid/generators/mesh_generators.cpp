#include "rebraid/generators/mesh_generators.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "rebraid/core/random.h"

namespace rebraid {
namespace {

constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;

/// Two triangles (a, b, c) and (a, c, d): counter-clockwise seen from the side where the
/// quad a->b->c->d turns counter-clockwise.
void add_quad(Mesh& mesh, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    mesh.triangles.push_back({a, b, c});
    mesh.triangles.push_back({a, c, d});
}

/// Appends `part` (its vertices and triangles, indices shifted) to `mesh`.
void append_mesh(Mesh& mesh, const Mesh& part) {
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), part.positions.begin(), part.positions.end());
    for (const Triangle& t : part.triangles)
        mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

/// One cross-section of a swept tube: its centre and two unit vectors spanning the plane
/// perpendicular to the path. `normal` x `binormal` points along the path.
struct TubeFrame {
    Vec3f center;
    Vec3f normal;
    Vec3f binormal;
};

/// A tube of circular cross-section through `frames`; if `is_closed_loop`, the last frame
/// joins the first. Winding is outward because binormal = tangent x normal.
Mesh sweep_tube(const std::vector<TubeFrame>& frames, float radius, std::uint32_t side_count,
                bool is_closed_loop) {
    Mesh mesh;
    mesh.positions.reserve(frames.size() * side_count);
    for (const TubeFrame& frame : frames)
        for (std::uint32_t s = 0; s < side_count; ++s) {
            const float angle = kTwoPi * static_cast<float>(s) / static_cast<float>(side_count);
            mesh.positions.push_back(frame.center + frame.normal * (radius * std::cos(angle)) +
                                     frame.binormal * (radius * std::sin(angle)));
        }
    const auto ring_count = static_cast<std::uint32_t>(frames.size());
    const std::uint32_t band_count = is_closed_loop ? ring_count : ring_count - 1;
    for (std::uint32_t k = 0; k < band_count; ++k) {
        const std::uint32_t next_k = (k + 1) % ring_count;
        for (std::uint32_t s = 0; s < side_count; ++s) {
            const std::uint32_t next_s = (s + 1) % side_count;
            add_quad(mesh, k * side_count + s, k * side_count + next_s,
                     next_k * side_count + next_s, next_k * side_count + s);
        }
    }
    return mesh;
}

/// Frame whose normal is `outward` made perpendicular to `tangent` (both need not be unit).
TubeFrame make_frame(Vec3f center, Vec3f tangent, Vec3f outward) {
    const Vec3f t = normalize(tangent);
    const Vec3f n = normalize(outward - t * dot(outward, t));
    return {center, n, cross(t, n)};
}

}  // namespace

Mesh make_uv_sphere(const UvSphereSettings& settings) {
    const std::uint32_t segments = std::max(settings.segment_count, 3u);
    const std::uint32_t rings = std::max(settings.ring_count, 2u);
    const float r = settings.radius;
    Mesh mesh;
    mesh.name = "uv_sphere";
    // Vertex 0 is the north pole, then rings 1..rings-1 of `segments` vertices, then the
    // south pole; the poles are shared so the surface is closed.
    mesh.positions.push_back({0.0f, r, 0.0f});
    for (std::uint32_t j = 1; j < rings; ++j) {
        const float theta =
            std::numbers::pi_v<float> * static_cast<float>(j) / static_cast<float>(rings);
        for (std::uint32_t i = 0; i < segments; ++i) {
            const float phi = kTwoPi * static_cast<float>(i) / static_cast<float>(segments);
            mesh.positions.push_back({r * std::sin(theta) * std::cos(phi), r * std::cos(theta),
                                      r * std::sin(theta) * std::sin(phi)});
        }
    }
    const auto south = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.push_back({0.0f, -r, 0.0f});

    auto ring_vertex = [&](std::uint32_t j, std::uint32_t i) {
        return 1 + (j - 1) * segments + (i % segments);
    };
    for (std::uint32_t i = 0; i < segments; ++i)
        mesh.triangles.push_back({0, ring_vertex(1, i + 1), ring_vertex(1, i)});
    for (std::uint32_t j = 1; j + 1 < rings; ++j)
        for (std::uint32_t i = 0; i < segments; ++i)
            add_quad(mesh, ring_vertex(j, i), ring_vertex(j, i + 1), ring_vertex(j + 1, i + 1),
                     ring_vertex(j + 1, i));
    for (std::uint32_t i = 0; i < segments; ++i)
        mesh.triangles.push_back({south, ring_vertex(rings - 1, i), ring_vertex(rings - 1, i + 1)});
    return mesh;
}

Mesh make_torus(const TorusSettings& settings) {
    const std::uint32_t major = std::max(settings.major_segment_count, 3u);
    const std::uint32_t minor = std::max(settings.minor_segment_count, 3u);
    // A torus is a closed tube along the circle of radius major_radius in the XZ plane.
    std::vector<TubeFrame> frames;
    frames.reserve(major);
    for (std::uint32_t i = 0; i < major; ++i) {
        const float u = kTwoPi * static_cast<float>(i) / static_cast<float>(major);
        const Vec3f radial{std::cos(u), 0.0f, std::sin(u)};
        const Vec3f tangent{-std::sin(u), 0.0f, std::cos(u)};
        frames.push_back(make_frame(radial * settings.major_radius, tangent, radial));
    }
    Mesh mesh = sweep_tube(frames, settings.minor_radius, minor, true);
    mesh.name = "torus";
    return mesh;
}

Mesh make_box(Vec3f half_extents) {
    Mesh mesh;
    mesh.name = "box";
    // Corner c has x, y, z at the max side when bits 0, 1, 2 of c are set.
    for (std::uint32_t c = 0; c < 8; ++c)
        mesh.positions.push_back({(c & 1u) ? half_extents.x : -half_extents.x,
                                  (c & 2u) ? half_extents.y : -half_extents.y,
                                  (c & 4u) ? half_extents.z : -half_extents.z});
    add_quad(mesh, 0, 4, 6, 2);  // -x
    add_quad(mesh, 1, 3, 7, 5);  // +x
    add_quad(mesh, 0, 1, 5, 4);  // -y
    add_quad(mesh, 2, 6, 7, 3);  // +y
    add_quad(mesh, 0, 2, 3, 1);  // -z
    add_quad(mesh, 4, 5, 7, 6);  // +z
    return mesh;
}

Mesh make_ground_grid(const GroundGridSettings& settings) {
    const std::uint32_t cells = std::max(settings.cell_count, 1u);
    const std::uint32_t side = cells + 1;
    Random random(settings.seed);
    const float phase_x = kTwoPi * random.next_float01();
    const float phase_z = kTwoPi * random.next_float01();
    const float frequency = kTwoPi * 2.5f / std::max(settings.size, 1e-6f);
    Mesh mesh;
    mesh.name = "ground";
    mesh.positions.reserve(std::size_t{side} * side);
    for (std::uint32_t iz = 0; iz < side; ++iz)
        for (std::uint32_t ix = 0; ix < side; ++ix) {
            const float x = settings.size * (static_cast<float>(ix) / cells - 0.5f);
            const float z = settings.size * (static_cast<float>(iz) / cells - 0.5f);
            // In [-dip_depth, 0]: gentle hollows, never a bump above the objects' base.
            const float wave =
                std::sin(frequency * x + phase_x) * std::sin(frequency * z + phase_z);
            mesh.positions.push_back({x, -settings.dip_depth * 0.5f * (1.0f + wave), z});
        }
    // Rows run along +x, columns along +z; x then z is clockwise seen from above, so each
    // quad is listed z first to face +Y.
    for (std::uint32_t iz = 0; iz < cells; ++iz)
        for (std::uint32_t ix = 0; ix < cells; ++ix) {
            const std::uint32_t a = iz * side + ix;
            add_quad(mesh, a, a + side, a + side + 1, a + 1);
        }
    return mesh;
}

Mesh make_tree(const TreeSettings& settings) {
    const std::uint32_t trunk_segments = std::max(settings.trunk_segment_count, 3u);
    const float trunk_r = settings.trunk_radius, trunk_h = settings.trunk_height;

    // Trunk: an open cylinder from y = 0 to trunk_h plus two fan caps.
    Mesh trunk;
    for (std::uint32_t ring = 0; ring < 2; ++ring)
        for (std::uint32_t i = 0; i < trunk_segments; ++i) {
            const float phi = kTwoPi * static_cast<float>(i) / static_cast<float>(trunk_segments);
            trunk.positions.push_back(
                {trunk_r * std::cos(phi), ring == 0 ? 0.0f : trunk_h, trunk_r * std::sin(phi)});
        }
    const std::uint32_t bottom_center = 2 * trunk_segments, top_center = bottom_center + 1;
    trunk.positions.push_back({0.0f, 0.0f, 0.0f});
    trunk.positions.push_back({0.0f, trunk_h, 0.0f});
    for (std::uint32_t i = 0; i < trunk_segments; ++i) {
        const std::uint32_t next = (i + 1) % trunk_segments;
        add_quad(trunk, i, trunk_segments + i, trunk_segments + next, next);
        trunk.triangles.push_back({bottom_center, i, next});
        trunk.triangles.push_back({top_center, trunk_segments + next, trunk_segments + i});
    }

    // Canopy: a unit sphere whose radius is modulated by a few seeded plane waves, so each
    // seed gives a different lumpy blob; lumpiness < 1 keeps the radius positive.
    Mesh canopy = make_uv_sphere({.radius = 1.0f,
                                  .segment_count = settings.canopy_segment_count,
                                  .ring_count = settings.canopy_ring_count});
    Random random(settings.seed);
    constexpr int kWaveCount = 4;
    std::array<Vec3f, kWaveCount> wave_vectors;
    std::array<float, kWaveCount> wave_phases;
    for (int w = 0; w < kWaveCount; ++w) {
        const Vec3f v{random.next_float(-1, 1), random.next_float(-1, 1), random.next_float(-1, 1)};
        wave_vectors[w] = v * (2.0f + 2.0f * static_cast<float>(w));
        wave_phases[w] = kTwoPi * random.next_float01();
    }
    const float lumpiness = std::clamp(settings.canopy_lumpiness, 0.0f, 0.9f);
    const Vec3f canopy_center{0.0f, trunk_h + 0.6f * settings.canopy_radius, 0.0f};
    for (Vec3f& p : canopy.positions) {
        float noise = 0.0f;
        for (int w = 0; w < kWaveCount; ++w)
            noise += std::sin(dot(wave_vectors[w], p) + wave_phases[w]) / kWaveCount;
        p = canopy_center + p * (settings.canopy_radius * (1.0f + lumpiness * noise));
    }

    Mesh mesh;
    mesh.name = "tree";
    append_mesh(mesh, trunk);
    append_mesh(mesh, canopy);
    return mesh;
}

Mesh make_torus_knot(const TorusKnotSettings& settings) {
    const std::uint32_t path_segments = std::max(settings.path_segment_count, 3u);
    const auto p = static_cast<float>(std::max(settings.p, 1u));
    const auto q = static_cast<float>(std::max(settings.q, 1u));
    const float big_r = settings.major_radius, small_r = settings.minor_radius;
    const Vec3f up{0.0f, 1.0f, 0.0f};
    std::vector<TubeFrame> frames;
    frames.reserve(path_segments);
    for (std::uint32_t k = 0; k < path_segments; ++k) {
        const float t = kTwoPi * static_cast<float>(k) / static_cast<float>(path_segments);
        const Vec3f radial{std::cos(p * t), 0.0f, std::sin(p * t)};
        const Vec3f along{-std::sin(p * t), 0.0f, std::cos(p * t)};
        // The curve is the torus core point plus `offset`, which circles the core q times.
        // The offset is perpendicular to the tangent (differentiate to check), so it is a
        // seam-free normal for the tube: no parallel transport needed.
        const Vec3f offset = (radial * std::cos(q * t) + up * std::sin(q * t)) * small_r;
        const Vec3f center = radial * big_r + offset;
        const Vec3f tangent = radial * (-small_r * q * std::sin(q * t)) +
                              along * (p * (big_r + small_r * std::cos(q * t))) +
                              up * (small_r * q * std::cos(q * t));
        frames.push_back(make_frame(center, tangent, offset));
    }
    Mesh mesh =
        sweep_tube(frames, settings.tube_radius, std::max(settings.tube_segment_count, 3u), true);
    mesh.name = "torus_knot";
    return mesh;
}

Mesh make_helix(const HelixSettings& settings) {
    const std::uint32_t path_segments = std::max(settings.path_segment_count, 1u);
    const float omega = kTwoPi * settings.turn_count;
    std::vector<TubeFrame> frames;
    frames.reserve(path_segments + 1);
    for (std::uint32_t k = 0; k <= path_segments; ++k) {
        const float t = static_cast<float>(k) / static_cast<float>(path_segments);
        const Vec3f radial{std::cos(omega * t), 0.0f, std::sin(omega * t)};
        const Vec3f center{settings.coil_radius * radial.x, settings.height * t,
                           settings.coil_radius * radial.z};
        const Vec3f tangent{-settings.coil_radius * omega * radial.z, settings.height,
                            settings.coil_radius * omega * radial.x};
        frames.push_back(make_frame(center, tangent, radial));
    }
    Mesh mesh =
        sweep_tube(frames, settings.tube_radius, std::max(settings.tube_segment_count, 3u), false);
    mesh.name = "helix";
    return mesh;
}

}  // namespace rebraid
