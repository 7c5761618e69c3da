#include "rebraid/bvh/vertex_world_bounds.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace rebraid {
namespace {

/// d · p with the products summed in the order AffineTransform::transform_vector uses.
float project(Vec3f d, Vec3f p) {
    return (d.x * p.x + d.y * p.y) + d.z * p.z;
}

/// The largest d · p over the corners of `box`: an upper bound for every point inside.
float box_bound(const BBox3f& box, Vec3f d) {
    return (d.x * (d.x > 0.0f ? box.max.x : box.min.x) +
            d.y * (d.y > 0.0f ? box.max.y : box.min.y)) +
           d.z * (d.z > 0.0f ? box.max.z : box.min.z);
}

/// A support value being searched: the best vertex projection found, and the largest bound
/// of a subtree skipped within the tolerance.
struct Support {
    float best = -std::numeric_limits<float>::infinity();
    float skipped = -std::numeric_limits<float>::infinity();
    Vec3f best_vertex{};
    float value() const { return std::max(best, skipped); }
    void offer(Vec3f d, Vec3f vertex) {
        const float projection = project(d, vertex);
        if (projection > best) {
            best = projection;
            best_vertex = vertex;
        }
    }
};

/// Raises `support` over the vertices of the triangles under `ref` along `d`, skipping
/// subtrees that cannot beat it by more than `slack`. Recursion depth is the object BVH's
/// depth; no allocation.
void raise_support(const ObjectBvh& bvh, NodeRef ref, Vec3f d, float slack, Support& support) {
    if (ref.is_empty()) return;
    if (ref.is_leaf()) {
        const std::uint32_t first = ref.first_prim();
        for (std::uint32_t i = first; i < first + ref.prim_count(); ++i) {
            const TriangleVerts& t = bvh.triangles[i];
            support.offer(d, t.v0);
            support.offer(d, t.v1);
            support.offer(d, t.v2);
        }
        return;
    }
    const WideNode& node = bvh.nodes[ref.node_id()];
    std::array<std::pair<float, int>, kBvhWidth> order;
    int count = 0;
    for (int c = 0; c < kBvhWidth && !node.children[c].is_empty(); ++c)
        order[count++] = {box_bound(node.child_bounds(c), d), c};
    // Most promising child first: its vertices raise the best early and prune its siblings.
    std::sort(order.begin(), order.begin() + count,
              [](const auto& a, const auto& b) { return a.first > b.first; });
    for (int i = 0; i < count; ++i) {
        const float bound = order[i].first;
        if (bound <= support.best) break;  // sorted: no later child can beat it either
        if (bound <= support.best + slack) {
            support.skipped = std::max(support.skipped, bound);
            continue;
        }
        raise_support(bvh, node.children[order[i].second], d, slack, support);
    }
}

float max_abs(Vec3f v) {
    return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
}

}  // namespace

VertexSupport vertex_support(const ObjectBvh& bvh, NodeRef node, Vec3f direction, float slack,
                             const Vec3f* start) {
    Support support;
    if (start) support.offer(direction, *start);
    raise_support(bvh, node, direction, slack, support);
    return {support.value(), support.best_vertex};
}

BBox3f vertex_world_bounds(const ObjectBvh& bvh, NodeRef node, const BBox3f& node_box,
                           const AffineTransform& to_world, float tolerance) {
    if (node.is_empty() || node_box.is_empty()) return BBox3f{};
    BBox3f box;
    for (int axis = 0; axis < 3; ++axis) {
        const Vec3f row{to_world.col_x[axis], to_world.col_y[axis], to_world.col_z[axis]};
        // The node's extent along the row bounds how far off a skipped subtree may be.
        const float slack = tolerance * (box_bound(node_box, row) + box_bound(node_box, -row));
        Support highest, lowest_negated;
        raise_support(bvh, node, row, slack, highest);
        raise_support(bvh, node, -row, slack, lowest_negated);
        box.min[axis] = -lowest_negated.value() + to_world.translation[axis];
        box.max[axis] = highest.value() + to_world.translation[axis];
    }
    // The projections and the sums above round: 8 ulps, like transformed leaf bounds
    // (bref_bounds.cpp).
    return widen_for_mapping_rounding(box, to_world,
                                      std::max(max_abs(node_box.min), max_abs(node_box.max)), 8.0f);
}

BBox3f widen_for_mapping_rounding(BBox3f box, const AffineTransform& to_world,
                                  float object_magnitude, float ulps) {
    const float matrix_magnitude =
        std::max({max_abs(to_world.col_x), max_abs(to_world.col_y), max_abs(to_world.col_z)});
    const float magnitude =
        std::max({3.0f * matrix_magnitude * object_magnitude, max_abs(to_world.translation),
                  max_abs(box.min), max_abs(box.max)});
    const float pad = magnitude * ulps * 0x1p-23f;
    box.min = box.min - Vec3f{pad, pad, pad};
    box.max = box.max + Vec3f{pad, pad, pad};
    return box;
}

}  // namespace rebraid
