#pragma once

// Boxes and rays for the box tests (the node test, the root-box cull): child boxes, some of
// them flat, and rays of every kind a slab test can get wrong: from near and far (1e5 away),
// aimed at corners and faces, along the planes, axis-parallel, and with intervals that end at,
// before or past the aimed-at point.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/types.h"

namespace rebraid::test {

/// A root node of `count` random child boxes inside [-2, 2]^3 (some of them flat).
inline std::vector<WideNode> random_root(std::mt19937& random, int count) {
    std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
    std::vector<WideNode> nodes(1, WideNode::make_empty());
    for (int slot = 0; slot < count; ++slot) {
        BBox3f box;
        box.extend(Vec3f{coordinate(random), coordinate(random), coordinate(random)});
        Vec3f corner{coordinate(random), coordinate(random), coordinate(random)};
        if (slot % 3 == 2) corner.y = box.min.y;  // a flat box, as a single planar triangle's
        box.extend(corner);
        nodes[0].set_child(slot, NodeRef::leaf(std::uint32_t(slot), 1), box);
    }
    return nodes;
}

/// Rays of every kind the cull must not get wrong: from anywhere near or far, aimed at the
/// children's corners and faces (the union box's planes are theirs), along the union box's
/// planes, with axis-parallel directions, and with intervals that end at, before or past it.
inline std::vector<Ray> rays_around(std::mt19937& random, const WideNode& root) {
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::uniform_real_distribution<float> fraction(0.0f, 1.0f);
    const BBox3f bounds = root.bounds();
    std::vector<Ray> rays;
    const auto origin_outside = [&](float distance) {
        Vec3f org{unit(random), unit(random), unit(random)};
        return org * (distance / std::max(1e-3f, length(org)));
    };
    for (int i = 0; i < 400; ++i) {
        const float distance = i % 4 == 0 ? 1e5f : 2.0f + 6.0f * fraction(random);
        const Vec3f org = origin_outside(distance);
        // At a corner of a child box, or at a point on one of its faces.
        const BBox3f child = root.child_bounds(i % root.child_count());
        Vec3f target{i & 1 ? child.max.x : child.min.x, i & 2 ? child.max.y : child.min.y,
                     i & 4 ? child.max.z : child.min.z};
        if (i % 5 == 0) target.x = child.min.x + fraction(random) * (child.max.x - child.min.x);
        Vec3f dir = target - org;
        if (i % 7 == 0) dir.y = 0.0f;  // parallel to the y planes
        if (i % 11 == 0) dir = {0.0f, 0.0f, target.z > org.z ? 1.0f : -1.0f};
        Ray ray{org, 0.0f, dir, std::numeric_limits<float>::infinity()};
        rays.push_back(ray);
        ray.tfar = 1.0f;  // ends at the target (dir is unnormalised)
        rays.push_back(ray);
        ray.tfar = std::nextafter(1.0f, 0.0f);
        rays.push_back(ray);
        ray.tnear = 1.0f;
        ray.tfar = std::numeric_limits<float>::infinity();
        rays.push_back(ray);
        ray.tnear = 2.0f;
        ray.tfar = 1.0f;  // an empty interval
        rays.push_back(ray);
    }
    // Along the union box's own planes, from outside it.
    for (int i = 0; i < 200; ++i) {
        const int axis = i % 3;
        Vec3f org = origin_outside(3.0f + fraction(random));
        org[axis] = i & 8 ? bounds.max[axis] : bounds.min[axis];
        Vec3f dir = Vec3f{unit(random), unit(random), unit(random)} * 0.5f - org * 0.1f;
        dir[axis] = 0.0f;
        rays.push_back(Ray{org, 0.0f, dir, std::numeric_limits<float>::infinity()});
    }
    // From inside the union box, and from anywhere in any direction.
    for (int i = 0; i < 400; ++i) {
        const Vec3f org = i % 2 ? bounds.center() + Vec3f{unit(random), unit(random), unit(random)}
                                : Vec3f{unit(random), unit(random), unit(random)} * 8.0f;
        rays.push_back(
            Ray{org, 0.0f, {unit(random), unit(random), unit(random)}, 20.0f * fraction(random)});
    }
    return rays;
}

}  // namespace rebraid::test
