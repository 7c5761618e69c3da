#pragma once

// Small procedural scenes for tests: instanced grids, heavy overlap, degenerate triangles,
// extreme coordinates, mirrored and scaled instances. Fixed seeds, built in milliseconds.

#include <cmath>
#include <string>
#include <vector>

#include "rebraid/core/random.h"
#include "rebraid/core/scene.h"
#include "rebraid/generators/mesh_generators.h"
#include "rebraid/generators/scene_generators.h"

namespace rebraid::test {

struct NamedScene {
    std::string name;
    Scene scene;
};

/// A mesh of `count` random small triangles in the unit cube (a soup: lots of overlap).
inline Mesh make_triangle_soup(std::uint32_t count, std::uint64_t seed, float size = 0.2f) {
    Random random(seed);
    Mesh mesh;
    mesh.name = "soup";
    for (std::uint32_t i = 0; i < count; ++i) {
        const Vec3f center{random.next_float01(), random.next_float01(), random.next_float01()};
        const auto base = std::uint32_t(mesh.positions.size());
        for (int c = 0; c < 3; ++c)
            mesh.positions.push_back(center + Vec3f{random.next_float(-size, size),
                                                    random.next_float(-size, size),
                                                    random.next_float(-size, size)});
        mesh.triangles.push_back({base, base + 1, base + 2});
    }
    return mesh;
}

/// Random rotation, non-uniform scale (optionally mirrored) and translation.
inline AffineTransform random_transform(Random& random, float spread, bool allow_mirror) {
    const Vec3f axis{random.next_float(-1, 1), random.next_float(-1, 1),
                     random.next_float(-1, 1) + 0.01f};
    Vec3f scale{random.next_float(0.5f, 2.0f), random.next_float(0.5f, 2.0f),
                random.next_float(0.5f, 2.0f)};
    if (allow_mirror && random.next_below(2) == 1) scale.x = -scale.x;
    const Vec3f offset{random.next_float(-spread, spread), random.next_float(-spread, spread),
                       random.next_float(-spread, spread)};
    return AffineTransform::translate(offset) *
           AffineTransform::rotate(axis, random.next_float(0.0f, 6.2831853f)) *
           AffineTransform::scale(scale);
}

/// Many rotated, scaled and mirrored instances of a few meshes crossing each other.
inline Scene make_overlap_scene(std::uint32_t instance_count, std::uint64_t seed) {
    Scene scene;
    scene.meshes.push_back(make_torus({.major_segment_count = 32, .minor_segment_count = 12}));
    scene.meshes.push_back(make_helix({.path_segment_count = 120, .tube_segment_count = 6}));
    scene.meshes.push_back(make_triangle_soup(500, seed));
    Random random(seed);
    for (std::uint32_t i = 0; i < instance_count; ++i)
        scene.instances.push_back(
            {MeshId(i % scene.meshes.size()), random_transform(random, 2.0f, true)});
    return scene;
}

/// Degenerate triangles (repeated corners, collinear corners) mixed with good ones, and
/// one-triangle meshes.
inline Scene make_degenerate_scene() {
    Scene scene;
    Mesh mixed = make_triangle_soup(200, 11);
    const auto n = std::uint32_t(mixed.positions.size());
    mixed.positions.push_back({0.5f, 0.5f, 0.5f});
    mixed.positions.push_back({0.6f, 0.6f, 0.6f});
    mixed.positions.push_back({0.7f, 0.7f, 0.7f});
    for (std::uint32_t i = 0; i < 50; ++i) {
        mixed.triangles.push_back({n, n, n});          // a point
        mixed.triangles.push_back({n, n + 1, n + 2});  // collinear
        mixed.triangles.push_back({n + 1, n + 1, n});  // a segment
    }
    scene.meshes.push_back(std::move(mixed));
    Mesh single;
    single.name = "single";
    single.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    single.triangles = {{0, 1, 2}};
    scene.meshes.push_back(std::move(single));
    Random random(5);
    for (std::uint32_t i = 0; i < 40; ++i)
        scene.instances.push_back({MeshId(i % 2), random_transform(random, 1.0f, true)});
    return scene;
}

/// The overlap scene scaled by `scale` and moved by `offset` (huge or tiny coordinates).
inline Scene make_scaled_scene(float scale, Vec3f offset) {
    Scene scene = make_overlap_scene(30, 23);
    for (Instance& instance : scene.instances)
        instance.object_to_world = AffineTransform::translate(offset) *
                                   AffineTransform::scale({scale, scale, scale}) *
                                   instance.object_to_world;
    return scene;
}

/// Every generated scene the equivalence tests run on.
inline std::vector<NamedScene> generated_scenes() {
    std::vector<NamedScene> scenes;
    scenes.push_back({"overlap", make_overlap_scene(200, 3)});
    scenes.push_back({"degenerate", make_degenerate_scene()});
    scenes.push_back({"huge", make_scaled_scene(1e5f, {3e6f, -1e6f, 2e6f})});
    scenes.push_back({"tiny", make_scaled_scene(1e-4f, {1e-3f, 0.0f, -2e-3f})});
    // Each family of `rebraid generate` (rebraid/generators/scene_generators.h), small.
    for (const auto& [kind, count] : {std::pair{SceneKind::kTrees, 30u},
                                      {SceneKind::kCrown, 80u},
                                      {SceneKind::kPowerplant, 2u},
                                      {SceneKind::kCity, 50u}})
        scenes.push_back({std::string(scene_kind_name(kind)),
                          generate_scene(kind, {.instance_count = count, .seed = 7})});
    return scenes;
}

}  // namespace rebraid::test
