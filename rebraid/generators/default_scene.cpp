#include "rebraid/generators/default_scene.h"

#include <cmath>
#include <numbers>

#include "rebraid/core/random.h"
#include "rebraid/generators/mesh_generators.h"

namespace rebraid {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

/// The layout of the default scene: "a grove crossed by chains". Y is up (glTF's convention)
/// and everything stands on the ground at y = 0. The numbers are chosen so instance boxes
/// overlap heavily (interlocking chain links, tilted reeds crossing trees and each other),
/// the case where re-braiding beats a plain two-level BVH, while the scene stays at about
/// 1.3 M instanced triangles so a flat BVH over it still builds quickly.
struct DefaultSceneLayout {
    std::uint64_t seed = 0x5eb7a1d;  ///< every random choice below comes from this
    float field_half_size = 14.0f;   ///< objects are placed in [-h, h]^2 on the ground
    float ground_size = 34.0f;       ///< the ground extends beyond the field
    std::uint32_t tree_grid = 9;     ///< trees on a jittered tree_grid x tree_grid lattice
    std::uint32_t chain_count = 8;   ///< arches of interlocking torus links
    float link_pitch = 0.85f;        ///< centre distance of consecutive links (< 2 x inner radius)
    std::uint32_t reed_count = 60;   ///< tall helices, tilted so they cross
    std::uint32_t knot_count = 40;
    std::uint32_t ball_count = 80;
};

/// Mesh ids in the order make_default_scene adds them.
enum DefaultMesh : MeshId { kGround, kTree, kLink, kKnot, kReed, kBall, kMeshCount };

Vec3f random_unit_vector(Random& random) {
    const float z = random.next_float(-1.0f, 1.0f);
    const float phi = random.next_float(0.0f, 2.0f * kPi);
    const float r = std::sqrt(std::fmax(0.0f, 1.0f - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Uniform scale about the origin.
AffineTransform scale_by(float s) {
    return AffineTransform::scale({s, s, s});
}

/// A rigid frame whose object X maps to `x_axis` and object Y to `y_axis` (unit, orthogonal).
AffineTransform frame(Vec3f x_axis, Vec3f y_axis, Vec3f origin) {
    return {x_axis, y_axis, cross(x_axis, y_axis), origin};
}

void add_trees(Scene& scene, const DefaultSceneLayout& layout, Random& random) {
    const float cell = 2.0f * layout.field_half_size / static_cast<float>(layout.tree_grid);
    for (std::uint32_t row = 0; row < layout.tree_grid; ++row)
        for (std::uint32_t col = 0; col < layout.tree_grid; ++col) {
            // Jitter by up to half a cell so canopies of neighbours overlap unevenly.
            const float x = -layout.field_half_size + cell * (static_cast<float>(col) + 0.5f +
                                                              random.next_float(-0.5f, 0.5f));
            const float z = -layout.field_half_size + cell * (static_cast<float>(row) + 0.5f +
                                                              random.next_float(-0.5f, 0.5f));
            const float yaw = random.next_float(0.0f, 2.0f * kPi);
            const float lean = random.next_float(0.0f, 0.15f);
            const Vec3f lean_axis{std::cos(yaw), 0.0f, std::sin(yaw)};
            const float size = random.next_float(0.8f, 1.3f);
            scene.instances.push_back({kTree, AffineTransform::translate({x, 0.0f, z}) *
                                                  AffineTransform::rotate(lean_axis, lean) *
                                                  AffineTransform::rotate({0, 1, 0}, yaw) *
                                                  scale_by(size)});
        }
}

/// Lowest link centre: the link's outer radius less a little, so the end links touch the
/// ground instead of sinking into it.
constexpr float kLinkMinHeight = 0.6f;

/// Chains of links hanging as parabolic arches between two ground points; consecutive links
/// are turned 90 degrees about the chain so they interlock like a real chain.
void add_chains(Scene& scene, const DefaultSceneLayout& layout, Random& random) {
    const float h = layout.field_half_size;
    const Vec3f up{0.0f, 1.0f, 0.0f};
    for (std::uint32_t c = 0; c < layout.chain_count; ++c) {
        const Vec3f start{random.next_float(-h, h), 0.0f, random.next_float(-h, h)};
        // Both feet in the field, 8 to 16 apart: redraw the far foot until it fits (the
        // stream stays deterministic, and a third of the field's points qualify).
        Vec3f end;
        do {
            end = {random.next_float(-h, h), 0.0f, random.next_float(-h, h)};
        } while (length(end - start) < 8.0f || length(end - start) > 16.0f);
        const float height = random.next_float(3.0f, 6.0f);
        auto point_at = [&](float s) {
            return start + (end - start) * s + up * (4.0f * height * s * (1.0f - s));
        };
        auto tangent_at = [&](float s) {
            return normalize((end - start) + up * (4.0f * height * (1.0f - 2.0f * s)));
        };
        // Walk the arch in small parameter steps and drop a link every link_pitch of length.
        const Vec3f side = normalize(cross(end - start, up));
        float travelled = layout.link_pitch;
        Vec3f previous = point_at(0.0f);
        std::uint32_t link = 0;
        constexpr int kSteps = 2000;
        for (int step = 1; step <= kSteps; ++step) {
            const float s = static_cast<float>(step) / kSteps;
            const Vec3f p = point_at(s);
            travelled += length(p - previous);
            previous = p;
            // Links start and end where the arch rises from the ground, not inside it.
            if (travelled < layout.link_pitch || p.y < kLinkMinHeight) continue;
            travelled = 0.0f;
            const Vec3f tangent = tangent_at(s);
            // The torus axis (object Y) is perpendicular to the chain; alternate between the
            // side vector and the in-plane normal.
            const Vec3f in_plane_normal = normalize(cross(side, tangent));
            const Vec3f axis = (link % 2 == 0) ? side : in_plane_normal;
            scene.instances.push_back({kLink, frame(tangent, axis, p)});
            ++link;
        }
    }
}

/// Tall thin springs standing on the ground, tilted in random directions so they cross the
/// trees, the chains and each other.
void add_reeds(Scene& scene, const DefaultSceneLayout& layout, Random& random) {
    const float h = layout.field_half_size;
    for (std::uint32_t r = 0; r < layout.reed_count; ++r) {
        const Vec3f base{random.next_float(-h, h), 0.0f, random.next_float(-h, h)};
        const float tilt_direction = random.next_float(0.0f, 2.0f * kPi);
        const Vec3f tilt_axis{std::cos(tilt_direction), 0.0f, std::sin(tilt_direction)};
        const float tilt = random.next_float(0.15f, 0.7f);
        const float spin = random.next_float(0.0f, 2.0f * kPi);
        const float size = random.next_float(0.7f, 1.2f);
        scene.instances.push_back(
            {kReed, AffineTransform::translate(base) * AffineTransform::rotate(tilt_axis, tilt) *
                        AffineTransform::rotate({0, 1, 0}, spin) * scale_by(size)});
    }
}

/// Knots in arbitrary orientations, resting on the ground (their rotated box touches y = 0).
void add_knots(Scene& scene, const DefaultSceneLayout& layout, Random& random,
               const BBox3f& knot_bounds) {
    const float h = layout.field_half_size;
    for (std::uint32_t k = 0; k < layout.knot_count; ++k) {
        const float size = random.next_float(0.5f, 0.9f);
        const float x = random.next_float(-h, h), z = random.next_float(-h, h);
        const Vec3f axis = random_unit_vector(random);
        const float angle = random.next_float(0.0f, 2.0f * kPi);
        const AffineTransform oriented = AffineTransform::rotate(axis, angle) * scale_by(size);
        const float lift = -oriented.transform_bbox(knot_bounds).min.y;
        scene.instances.push_back({kKnot, AffineTransform::translate({x, lift, z}) * oriented});
    }
}

/// Balls of several sizes lying on the ground.
void add_balls(Scene& scene, const DefaultSceneLayout& layout, Random& random) {
    const float h = layout.field_half_size;
    for (std::uint32_t b = 0; b < layout.ball_count; ++b) {
        const float radius = random.next_float(0.25f, 0.7f);
        const Vec3f center{random.next_float(-h, h), radius, random.next_float(-h, h)};
        scene.instances.push_back({kBall, AffineTransform::translate(center) * scale_by(radius)});
    }
}

}  // namespace

Scene make_default_scene() {
    const DefaultSceneLayout layout;
    Scene scene;
    scene.meshes.resize(kMeshCount);
    scene.meshes[kGround] = make_ground_grid({.size = layout.ground_size, .cell_count = 128});
    scene.meshes[kTree] = make_tree({});
    scene.meshes[kLink] = make_torus({.major_radius = 0.6f, .minor_radius = 0.13f});
    scene.meshes[kKnot] = make_torus_knot({});
    scene.meshes[kReed] = make_helix({});
    scene.meshes[kBall] = make_uv_sphere({.radius = 1.0f});

    // One random stream, consumed in a fixed order, fixes every placement.
    Random random(layout.seed);
    scene.instances.push_back({kGround, AffineTransform::identity()});
    add_trees(scene, layout, random);
    add_chains(scene, layout, random);
    add_reeds(scene, layout, random);
    add_knots(scene, layout, random, scene.meshes[kKnot].bounds());
    add_balls(scene, layout, random);
    return scene;
}

}  // namespace rebraid
