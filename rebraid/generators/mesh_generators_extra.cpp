#include "rebraid/generators/mesh_generators_extra.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <utility>
#include <vector>

#include "rebraid/core/random.h"
#include "rebraid/generators/mesh_generators.h"

namespace rebraid {
namespace {

constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;

/// Triangles (a, b, c) and (a, c, d).
void add_quad(Mesh& mesh, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    mesh.triangles.push_back({a, b, c});
    mesh.triangles.push_back({a, c, d});
}

/// Appends `part` mapped by `transform` (which must not mirror, so winding stays outward).
void append_transformed(Mesh& mesh, const Mesh& part, const AffineTransform& transform) {
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (const Vec3f& p : part.positions) mesh.positions.push_back(transform.transform_point(p));
    for (const Triangle& t : part.triangles)
        mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

/// The box [-0.5, 0.5]^3 with its four sides along X cut into `segment_count` slices, so a
/// long bar made from it has no triangle longer than a slice: long thin triangles would give
/// every BVH over the part huge, mostly empty boxes once the part is rotated. Triangles:
/// 8 * segment_count + 4, wound outward.
Mesh make_unit_bar(std::uint32_t segment_count) {
    const std::uint32_t n = std::max(segment_count, 1u);
    // Ring k (at x = -0.5 + k / n) holds corners (y, z) in the order below, 4k + j.
    constexpr float kRing[4][2] = {{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
    Mesh mesh;
    for (std::uint32_t k = 0; k <= n; ++k)
        for (const auto& corner : kRing)
            mesh.positions.push_back(
                {-0.5f + static_cast<float>(k) / static_cast<float>(n), corner[0], corner[1]});
    // Quad a-b-c-d, turned around when its normal points against `outward`.
    auto add_outward = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d,
                           Vec3f outward) {
        const Vec3f& pa = mesh.positions[a];
        if (dot(cross(mesh.positions[b] - pa, mesh.positions[c] - pa), outward) < 0.0f)
            std::swap(b, d);
        add_quad(mesh, a, b, c, d);
    };
    for (std::uint32_t k = 0; k < n; ++k)
        for (std::uint32_t j = 0; j < 4; ++j) {
            const std::uint32_t next = (j + 1) % 4;
            const Vec3f outward{0.0f, kRing[j][0] + kRing[next][0], kRing[j][1] + kRing[next][1]};
            add_outward(4 * k + j, 4 * (k + 1) + j, 4 * (k + 1) + next, 4 * k + next, outward);
        }
    add_outward(0, 1, 2, 3, {-1.0f, 0.0f, 0.0f});
    add_outward(4 * n, 4 * n + 1, 4 * n + 2, 4 * n + 3, {1.0f, 0.0f, 0.0f});
    return mesh;
}

/// Appends the axis-aligned box [lo, hi], its sides along X cut into `segment_count` slices.
void append_box(Mesh& mesh, Vec3f lo, Vec3f hi, std::uint32_t segment_count = 1) {
    append_transformed(
        mesh, make_unit_bar(segment_count),
        AffineTransform::translate((lo + hi) * 0.5f) * AffineTransform::scale(hi - lo));
}

/// Appends a square bar of side `thickness` from `a` to `b`, cut into `segment_count` slices
/// along its length.
void append_bar(Mesh& mesh, Vec3f a, Vec3f b, float thickness, std::uint32_t segment_count = 1) {
    const Vec3f along = normalize(b - a);
    const Vec3f helper = std::fabs(along.y) < 0.9f ? Vec3f{0, 1, 0} : Vec3f{1, 0, 0};
    const Vec3f side = normalize(cross(helper, along));
    // (along, side, along x side) is right-handed, so the box keeps its outward winding.
    append_transformed(mesh, make_unit_bar(segment_count),
                       {b - a, side * thickness, cross(along, side) * thickness, (a + b) * 0.5f});
}

/// A point of a profile revolved about the Y axis: its distance from the axis and height.
struct ProfilePoint {
    float radius = 0.0f;
    float y = 0.0f;
};

/// Surface of revolution about Y: profile point k at angle phi is `profile(k, phi)`, for
/// k in [0, point_count). A point whose radius is 0 at phi = 0 is a pole (one shared vertex).
/// The profile must run counter-clockwise in the (radius, y) plane, the solid on its left,
/// for outward winding; `is_closed_loop` joins the last point back to the first.
Mesh revolve(std::uint32_t point_count, std::uint32_t segment_count, bool is_closed_loop,
             const std::function<ProfilePoint(std::uint32_t, float)>& profile) {
    Mesh mesh;
    std::vector<std::uint32_t> first_vertex(point_count);
    std::vector<bool> is_pole(point_count);
    for (std::uint32_t k = 0; k < point_count; ++k) {
        first_vertex[k] = static_cast<std::uint32_t>(mesh.positions.size());
        is_pole[k] = profile(k, 0.0f).radius == 0.0f;
        const std::uint32_t ring_size = is_pole[k] ? 1 : segment_count;
        for (std::uint32_t i = 0; i < ring_size; ++i) {
            const float phi = kTwoPi * static_cast<float>(i) / static_cast<float>(segment_count);
            const ProfilePoint p = profile(k, phi);
            mesh.positions.push_back({p.radius * std::cos(phi), p.y, p.radius * std::sin(phi)});
        }
    }
    auto vertex = [&](std::uint32_t k, std::uint32_t i) {
        return is_pole[k] ? first_vertex[k] : first_vertex[k] + i % segment_count;
    };
    const std::uint32_t edge_count = is_closed_loop ? point_count : point_count - 1;
    for (std::uint32_t e = 0; e < edge_count; ++e) {
        const std::uint32_t k = e, next_k = (e + 1) % point_count;
        if (is_pole[k] && is_pole[next_k]) continue;
        for (std::uint32_t i = 0; i < segment_count; ++i) {
            const std::uint32_t a = vertex(k, i), b = vertex(next_k, i);
            const std::uint32_t c = vertex(next_k, i + 1), d = vertex(k, i + 1);
            if (is_pole[k])
                mesh.triangles.push_back({a, b, c});
            else if (is_pole[next_k])
                mesh.triangles.push_back({a, b, d});
            else
                add_quad(mesh, a, b, c, d);
        }
    }
    return mesh;
}

Vec3f random_unit_vector(Random& random) {
    const float z = random.next_float(-1.0f, 1.0f);
    const float phi = random.next_float(0.0f, kTwoPi);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Some unit vector perpendicular to the unit vector `v`.
Vec3f any_perpendicular(Vec3f v) {
    const Vec3f helper = std::fabs(v.y) < 0.9f ? Vec3f{0, 1, 0} : Vec3f{1, 0, 0};
    return normalize(cross(helper, v));
}

/// Grows the branches of make_branching_tree depth first, so the vertex order is fixed.
class TreeGrower {
public:
    TreeGrower(const BranchingTreeSettings& settings, Mesh& mesh)
        : settings_(settings),
          mesh_(mesh),
          random_(settings.seed),
          segment_count_(std::max(settings.segment_count, 3u)),
          branch_count_(std::clamp(settings.branch_count, 1u, 8u)),
          level_count_(std::min(settings.level_count, 6u)) {}

    void grow(Vec3f base, Vec3f direction, float length, float radius, std::uint32_t level) {
        const Vec3f tip = base + direction * length;
        const float tip_radius = radius * settings_.radius_ratio;
        add_branch(base, tip, direction, radius, tip_radius);
        if (level == level_count_) {
            add_leaves(tip);
            return;
        }
        const Vec3f normal = any_perpendicular(direction);
        const Vec3f binormal = cross(direction, normal);
        const float twist = random_.next_float(0.0f, kTwoPi);
        for (std::uint32_t c = 0; c < branch_count_; ++c) {
            const float azimuth = twist + kTwoPi * static_cast<float>(c) / branch_count_ +
                                  random_.next_float(-0.3f, 0.3f);
            const float tilt = settings_.branch_angle * random_.next_float(0.8f, 1.2f);
            Vec3f child =
                direction * std::cos(tilt) +
                (normal * std::cos(azimuth) + binormal * std::sin(azimuth)) * std::sin(tilt);
            child = normalize(child + Vec3f{0.0f, 0.15f, 0.0f});  // branches reach for light
            const float child_length =
                length * settings_.length_ratio * random_.next_float(0.85f, 1.15f);
            grow(tip, child, child_length, tip_radius, level + 1);
        }
    }

private:
    /// An open tapered tube from `base` to `tip`.
    void add_branch(Vec3f base, Vec3f tip, Vec3f direction, float base_radius, float tip_radius) {
        const Vec3f normal = any_perpendicular(direction);
        const Vec3f binormal = cross(direction, normal);  // normal x binormal = direction
        const auto first = static_cast<std::uint32_t>(mesh_.positions.size());
        const std::uint32_t n = segment_count_;
        for (int end = 0; end < 2; ++end)
            for (std::uint32_t s = 0; s < n; ++s) {
                const float angle = kTwoPi * static_cast<float>(s) / static_cast<float>(n);
                const Vec3f offset = normal * std::cos(angle) + binormal * std::sin(angle);
                mesh_.positions.push_back(end == 0 ? base + offset * base_radius
                                                   : tip + offset * tip_radius);
            }
        for (std::uint32_t s = 0; s < n; ++s) {
            const std::uint32_t next = (s + 1) % n;
            add_quad(mesh_, first + s, first + next, first + n + next, first + n + s);
        }
    }

    /// Square leaves scattered in a ball around `tip`, each facing a random direction.
    void add_leaves(Vec3f tip) {
        const float half = 0.5f * settings_.leaf_size;
        for (std::uint32_t l = 0; l < settings_.leaf_count; ++l) {
            // Cube root of a uniform number: uniform density in the ball.
            const float distance = settings_.leaf_spread * std::cbrt(random_.next_float01());
            const Vec3f center = tip + random_unit_vector(random_) * distance;
            const Vec3f facing = random_unit_vector(random_);
            const Vec3f u = any_perpendicular(facing) * half;
            const Vec3f v = cross(facing, u);
            const auto first = static_cast<std::uint32_t>(mesh_.positions.size());
            mesh_.positions.push_back(center - u - v);
            mesh_.positions.push_back(center + u - v);
            mesh_.positions.push_back(center + u + v);
            mesh_.positions.push_back(center - u + v);
            add_quad(mesh_, first, first + 1, first + 2, first + 3);
        }
    }

    const BranchingTreeSettings& settings_;
    Mesh& mesh_;
    Random random_;
    std::uint32_t segment_count_;
    std::uint32_t branch_count_;
    std::uint32_t level_count_;
};

}  // namespace

Mesh make_cylinder(const CylinderSettings& settings) {
    const std::uint32_t rows = std::max(settings.length_segment_count, 1u);
    const float r = settings.radius, h = settings.height;
    // Profile (counter-clockwise): bottom centre, up the wall, top centre.
    const std::uint32_t cap = settings.is_capped ? 1 : 0;
    Mesh mesh = revolve(rows + 1 + 2 * cap, std::max(settings.segment_count, 3u), false,
                        [&](std::uint32_t k, float) -> ProfilePoint {
                            if (cap && k == 0) return {0.0f, 0.0f};
                            if (cap && k == rows + 2) return {0.0f, h};
                            const std::uint32_t row = k - cap;
                            return {r, h * static_cast<float>(row) / static_cast<float>(rows)};
                        });
    mesh.name = "cylinder";
    return mesh;
}

Mesh make_branching_tree(const BranchingTreeSettings& settings) {
    Mesh mesh;
    mesh.name = "branching_tree";
    TreeGrower(settings, mesh)
        .grow({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, settings.trunk_height, settings.trunk_radius,
              0);
    return mesh;
}

Mesh make_conifer(const ConiferSettings& settings) {
    const std::uint32_t tiers = std::max(settings.tier_count, 1u);
    const std::uint32_t segments = std::max(settings.segment_count, 3u);
    const std::uint32_t rings = std::max(settings.ring_count, 1u);
    const float jaggedness = std::clamp(settings.jaggedness, 0.0f, 0.9f);
    Mesh mesh;
    mesh.name = "conifer";
    // The trunk reaches into the lowest tier so no gap shows between them.
    const float crown_start = settings.trunk_height;
    const float step = (settings.height - crown_start) / static_cast<float>(tiers + 1);
    append_transformed(
        mesh,
        make_cylinder(
            {.radius = settings.trunk_radius, .height = crown_start + step, .segment_count = 8}),
        AffineTransform::identity());
    Random random(settings.seed);
    for (std::uint32_t t = 0; t < tiers; ++t) {
        // Tier t spans two steps, so each tier overlaps the next one's lower half.
        const float base_y = crown_start + step * static_cast<float>(t);
        const float top_y = base_y + 2.0f * step;
        const float underside_y = base_y + 0.3f * step;
        const float radius = settings.base_radius *
                             (1.0f - static_cast<float>(t) / (static_cast<float>(tiers) + 0.5f));
        // Integer frequencies keep the rim continuous where phi wraps around.
        const float f1 = static_cast<float>(5 + random.next_below(5));
        const float f2 = static_cast<float>(11 + random.next_below(7));
        const float p1 = random.next_float(0.0f, kTwoPi), p2 = random.next_float(0.0f, kTwoPi);
        // Profile: underside centre, rim, rings up the cone, apex.
        Mesh tier = revolve(rings + 2, segments, false, [&](std::uint32_t k, float phi) {
            if (k == 0) return ProfilePoint{0.0f, underside_y};
            if (k == rings + 1) return ProfilePoint{0.0f, top_y};
            const float along = static_cast<float>(k - 1) / static_cast<float>(rings);
            const float jag = 0.5f * (std::sin(f1 * phi + p1) + std::sin(f2 * phi + p2));
            const float wobble = 1.0f + jaggedness * jag * (1.0f - along);
            // Slightly concave cone: the rim droops like real branches.
            return ProfilePoint{radius * std::pow(1.0f - along, 1.3f) * wobble,
                                base_y + (top_y - base_y) * along};
        });
        append_transformed(mesh, tier, AffineTransform::identity());
    }
    return mesh;
}

Mesh make_ring_band(const RingBandSettings& settings) {
    const float outer = settings.radius;
    const float inner = std::max(outer - settings.thickness, 0.05f * outer);
    const float crests = static_cast<float>(settings.crest_count);
    auto top = [&](float phi) {
        if (settings.crest_count == 0) return settings.height;
        const float wave = 0.5f + 0.5f * std::cos(crests * phi);
        return settings.height + settings.crest_height * wave * wave * wave * wave;
    };
    // Closed profile: inner bottom -> outer bottom -> outer top -> inner top.
    Mesh mesh = revolve(4, std::max(settings.segment_count, 3u), true,
                        [&](std::uint32_t k, float phi) -> ProfilePoint {
                            switch (k) {
                                case 0:
                                    return {inner, 0.0f};
                                case 1:
                                    return {outer, 0.0f};
                                case 2:
                                    return {outer, top(phi)};
                                default:
                                    return {inner, top(phi)};
                            }
                        });
    mesh.name = "ring_band";
    return mesh;
}

Mesh make_gem(const GemSettings& settings) {
    const float r = settings.radius;
    // Profile: culet, girdle, table rim, table centre.
    Mesh mesh = revolve(4, std::max(settings.facet_count, 3u), false,
                        [&](std::uint32_t k, float) -> ProfilePoint {
                            switch (k) {
                                case 0:
                                    return {0.0f, -settings.pavilion_depth * r};
                                case 1:
                                    return {r, 0.0f};
                                case 2:
                                    return {settings.table_ratio * r, settings.crown_height * r};
                                default:
                                    return {0.0f, settings.crown_height * r};
                            }
                        });
    mesh.name = "gem";
    return mesh;
}

Mesh make_i_beam(const IBeamSettings& settings) {
    const float x = 0.5f * settings.length, y = 0.5f * settings.height, z = 0.5f * settings.width;
    const float flange = settings.flange_thickness, web = 0.5f * settings.web_thickness;
    Mesh mesh;
    mesh.name = "i_beam";
    const std::uint32_t n = settings.length_segment_count;
    append_box(mesh, {-x, y - flange, -z}, {x, y, z}, n);
    append_box(mesh, {-x, -y, -z}, {x, -y + flange, z}, n);
    append_box(mesh, {-x, -y + flange, -web}, {x, y - flange, web}, n);
    return mesh;
}

Mesh make_flanged_pipe(const FlangedPipeSettings& settings) {
    const std::uint32_t segments = std::max(settings.segment_count, 3u);
    // Cylinders are built along +Y from 0; this turns +Y into +X (a rotation, det = +1).
    auto along_x = [](float start_x) {
        return AffineTransform{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}, {start_x, 0, 0}};
    };
    Mesh mesh;
    mesh.name = "flanged_pipe";
    append_transformed(mesh,
                       make_cylinder({.radius = settings.radius,
                                      .height = settings.length,
                                      .segment_count = segments,
                                      .length_segment_count = settings.length_segment_count}),
                       along_x(-0.5f * settings.length));
    const Mesh flange = make_cylinder({.radius = settings.flange_radius,
                                       .height = settings.flange_width,
                                       .segment_count = segments});
    const float span = settings.length - settings.flange_width;
    for (std::uint32_t f = 0; f < settings.flange_count; ++f) {
        const float at =
            settings.flange_count == 1
                ? 0.5f
                : static_cast<float>(f) / static_cast<float>(settings.flange_count - 1);
        append_transformed(mesh, flange, along_x(-0.5f * settings.length + span * at));
    }
    return mesh;
}

Mesh make_truss(const TrussSettings& settings) {
    const std::uint32_t panels = std::max(settings.panel_count, 1u);
    const float half_length = 0.5f * settings.length, h = 0.5f * settings.width;
    const float t = settings.bar_thickness;
    Mesh mesh;
    mesh.name = "truss";
    // Chord corners in the YZ cross-section, in order around it; side s joins corners s, s+1.
    const float corners[4][2] = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
    for (const auto& c : corners)
        append_bar(mesh, {-half_length, c[0], c[1]}, {half_length, c[0], c[1]}, t, panels);
    for (int side = 0; side < 4; ++side) {
        const auto& from = corners[side];
        const auto& to = corners[(side + 1) % 4];
        for (std::uint32_t p = 0; p < panels; ++p) {
            const float x0 = -half_length + settings.length * static_cast<float>(p) / panels;
            const float x1 = -half_length + settings.length * static_cast<float>(p + 1) / panels;
            // Alternate the diagonal's direction: a zigzag, as in a Warren truss.
            const bool flip = p % 2 == 1;
            append_bar(mesh, {x0, flip ? to[0] : from[0], flip ? to[1] : from[1]},
                       {x1, flip ? from[0] : to[0], flip ? from[1] : to[1]}, t);
        }
    }
    return mesh;
}

Mesh make_building(const BuildingSettings& settings) {
    const std::uint32_t tiers = std::max(settings.tier_count, 1u);
    // Clamped so ledges and pilasters always fit in the footprint and loops stay short.
    const float relief =
        std::clamp(settings.relief, 0.0f, 0.25f * std::min(settings.width, settings.depth));
    const float floor_height = std::max(settings.floor_height, 0.001f * settings.height);
    const float bay =
        std::max(settings.bay_width, 0.001f * std::max(settings.width, settings.depth));
    Mesh mesh;
    mesh.name = "building";
    // Tier heights fall off upwards (weights tiers, tiers-1, ..., 1).
    const float weight_sum = 0.5f * static_cast<float>(tiers * (tiers + 1));
    float base_y = 0.0f;
    float half_w = 0.5f * settings.width - relief, half_d = 0.5f * settings.depth - relief;
    for (std::uint32_t t = 0; t < tiers; ++t) {
        const float tier_height = settings.height * static_cast<float>(tiers - t) / weight_sum;
        const float top_y = base_y + tier_height;
        append_box(mesh, {-half_w, base_y, -half_d}, {half_w, top_y, half_d});
        // A ledge at every floor, standing out by `relief` (so within the footprint).
        const float ledge = 0.15f * floor_height;
        const auto floors = static_cast<std::uint32_t>(tier_height / floor_height);
        for (std::uint32_t f = 1; f < floors; ++f) {
            const float y = base_y + floor_height * static_cast<float>(f);
            append_box(mesh, {-half_w - relief, y, -half_d - relief},
                       {half_w + relief, y + ledge, half_d + relief});
        }
        // Pilasters on the four facades, `bay` apart, none at the corners.
        const float pilaster = 0.4f * relief + 0.1f * bay;
        const auto bays_x = static_cast<std::uint32_t>(2.0f * half_w / bay);
        for (std::uint32_t b = 1; b < bays_x; ++b) {
            const float x = -half_w + 2.0f * half_w * static_cast<float>(b) / bays_x;
            append_box(mesh, {x - pilaster, base_y, half_d},
                       {x + pilaster, top_y, half_d + relief});
            append_box(mesh, {x - pilaster, base_y, -half_d - relief},
                       {x + pilaster, top_y, -half_d});
        }
        const auto bays_z = static_cast<std::uint32_t>(2.0f * half_d / bay);
        for (std::uint32_t b = 1; b < bays_z; ++b) {
            const float z = -half_d + 2.0f * half_d * static_cast<float>(b) / bays_z;
            append_box(mesh, {half_w, base_y, z - pilaster},
                       {half_w + relief, top_y, z + pilaster});
            append_box(mesh, {-half_w - relief, base_y, z - pilaster},
                       {-half_w, top_y, z + pilaster});
        }
        base_y = top_y;
        half_w *= 1.0f - settings.setback;
        half_d *= 1.0f - settings.setback;
    }
    // Machine room on the roof.
    append_box(mesh, {-0.4f * half_w, base_y, -0.4f * half_d},
               {0.4f * half_w, base_y + 0.04f * settings.height, 0.4f * half_d});
    return mesh;
}

}  // namespace rebraid
