#include "rebraid/bvh/support_table.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rebraid/bvh/vertex_world_bounds.h"

namespace rebraid {
namespace {

float max_abs(Vec3f v) {
    return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
}

/// The grid direction (i, j) of cube face `face`: face / 2 is the axis whose component is
/// +1 (even face) or -1 (odd face); the next two axes in cyclic order run from -1 to 1.
Vec3f grid_direction(int face, int i, int j, int cells) {
    const int axis = face / 2;
    Vec3f d{};
    d[axis] = face % 2 == 0 ? 1.0f : -1.0f;
    d[(axis + 1) % 3] = -1.0f + 2.0f * float(i) / float(cells);
    d[(axis + 2) % 3] = -1.0f + 2.0f * float(j) / float(cells);
    return d;
}

/// The extent of `box` along `d`: the range of d · p over its points.
float extent_along(const BBox3f& box, Vec3f d) {
    float extent = 0.0f;
    for (int axis = 0; axis < 3; ++axis)
        extent += std::fabs(d[axis]) * (box.max[axis] - box.min[axis]);
    return extent;
}

}  // namespace

SupportTable::SupportTable(const ObjectBvh& bvh, NodeRef node, const BBox3f& node_box,
                           float tolerance) {
    if (node.is_empty() || node_box.is_empty()) return;
    is_empty_ = false;
    center_ = (node_box.min + node_box.max) * 0.5f;
    half_extent_ = (node_box.max - node_box.min) * 0.5f;
    object_magnitude_ = std::max(max_abs(node_box.min), max_abs(node_box.max));
    for (int face = 0; face < 6; ++face) {
        // Each search starts from the extreme vertex of the previous, nearby direction.
        Vec3f previous{};
        bool has_previous = false;
        for (int i = 0; i < kSide; ++i)
            for (int j = 0; j < kSide; ++j) {
                const int row_j = i % 2 == 0 ? j : kCells - j;  // snake order: always a neighbour
                const Vec3f d = grid_direction(face, i, row_j, kCells);
                const VertexSupport found =
                    vertex_support(bvh, node, d, tolerance * extent_along(node_box, d),
                                   has_previous ? &previous : nullptr);
                if (found.value == -std::numeric_limits<float>::infinity()) {
                    is_empty_ = true;  // no vertex under the node: nothing to bound
                    return;
                }
                previous = found.vertex;  // a real vertex: a valid start for the next search
                has_previous = true;
                // Relative to the centre, in double, then widened by 8 ulps of the terms: the
                // projections in vertex_support round at the object's magnitude.
                const double relative =
                    double(found.value) -
                    (double(d.x) * center_.x + double(d.y) * center_.y + double(d.z) * center_.z);
                const double pad = 3.0 * double(object_magnitude_) * 0x1p-20;
                values_[index(face, i, row_j)] = float(relative + pad);
                vertices_[index(face, i, row_j)] = found.vertex;
            }
    }
}

SupportTable::SupportBounds SupportTable::support_bounds(Vec3f direction) const {
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (std::fabs(direction[k]) > std::fabs(direction[axis])) axis = k;
    const float scale = std::fabs(direction[axis]);
    if (scale == 0.0f) return {0.0f, center_};  // every vertex projects to 0
    const int face = 2 * axis + (direction[axis] < 0.0f ? 1 : 0);
    // The direction scaled onto the cube face: both coordinates in [-1, 1] (|a| <= |b| gives
    // |a / b| <= 1 in rounded division too).
    const float x = (direction[(axis + 1) % 3] / scale + 1.0f) * (0.5f * kCells);
    const float y = (direction[(axis + 2) % 3] / scale + 1.0f) * (0.5f * kCells);
    const int i = std::min(int(x), kCells - 1);
    const int j = std::min(int(y), kCells - 1);
    const float a = x - float(i), b = y - float(j);
    // Barycentric weights in the square's lower (a >= b) or upper triangle; the diagonal
    // corners (i, j) and (i + 1, j + 1) belong to both.
    const bool is_lower = a >= b;
    const int corners[3] = {index(face, i, j),
                            is_lower ? index(face, i + 1, j) : index(face, i, j + 1),
                            index(face, i + 1, j + 1)};
    const float weights[3] = {is_lower ? 1.0f - a : 1.0f - b, is_lower ? a - b : b - a,
                              is_lower ? b : a};
    float upper = 0.0f, best_projection = -std::numeric_limits<float>::infinity();
    Vec3f best_vertex = center_;
    for (int k = 0; k < 3; ++k) {
        upper += weights[k] * values_[corners[k]];
        const float projection = dot(direction, vertices_[corners[k]]);
        if (projection > best_projection) {
            best_projection = projection;
            best_vertex = vertices_[corners[k]];
        }
    }
    return {scale * upper, best_vertex};
}

float SupportTable::interpolated_upper(int face, float x, float y) const {
    const int i = std::min(int(x), kCells - 1);
    const int j = std::min(int(y), kCells - 1);
    const float a = x - float(i), b = y - float(j);
    // As support_bounds: the same corners, weights and sum, in the same order.
    const bool is_lower = a >= b;
    const float w0 = is_lower ? 1.0f - a : 1.0f - b;
    const float w1 = is_lower ? a - b : b - a;
    const float w2 = is_lower ? b : a;
    const float v1 = values_[is_lower ? index(face, i + 1, j) : index(face, i, j + 1)];
    float upper = 0.0f;
    upper += w0 * values_[index(face, i, j)];
    upper += w1 * v1;
    upper += w2 * values_[index(face, i + 1, j + 1)];
    return upper;
}

std::pair<float, float> SupportTable::upper_supports(Vec3f direction) const {
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (std::fabs(direction[k]) > std::fabs(direction[axis])) axis = k;
    const float scale = std::fabs(direction[axis]);
    if (scale == 0.0f) return {0.0f, 0.0f};
    // The faces of `direction` and of its negation are opposite; the scaled coordinates of
    // the negation are the negated quotients (division is exact in sign), so both come from
    // one pair of divisions with the arithmetic support_bounds uses for each.
    const int face = 2 * axis + (direction[axis] < 0.0f ? 1 : 0);
    const float u = direction[(axis + 1) % 3] / scale;
    const float v = direction[(axis + 2) % 3] / scale;
    constexpr float kHalfCells = 0.5f * kCells;
    const float along = interpolated_upper(face, (u + 1.0f) * kHalfCells, (v + 1.0f) * kHalfCells);
    const float against =
        interpolated_upper(face ^ 1, (-u + 1.0f) * kHalfCells, (-v + 1.0f) * kHalfCells);
    return {scale * along, scale * against};
}

BBox3f SupportTable::table_world_bounds(const AffineTransform& to_world) const {
    if (is_empty_) return BBox3f{};
    BBox3f box;
    for (int axis = 0; axis < 3; ++axis) {
        const Vec3f row{to_world.col_x[axis], to_world.col_y[axis], to_world.col_z[axis]};
        const float center = dot(row, center_) + to_world.translation[axis];
        const auto [along, against] = upper_supports(row);
        box.min[axis] = center - against;
        box.max[axis] = center + along;
    }
    // As world_bounds: the weights, the sums and the mapped centre round.
    return widen_for_mapping_rounding(box, to_world, object_magnitude_, 32.0f);
}

BBox3f SupportTable::world_bounds(const AffineTransform& to_world, const ObjectBvh& bvh,
                                  NodeRef node, float tolerance) const {
    if (is_empty_) return BBox3f{};
    // The largest projection onto `d` of a vertex, relative to the centre: from the table
    // when its bounds agree to within the tolerance, else by a search started at the best
    // corner vertex.
    auto support = [&](Vec3f d) {
        const SupportBounds bounds = support_bounds(d);
        const float slack = tolerance * 2.0f *
                            (std::fabs(d.x) * half_extent_.x + std::fabs(d.y) * half_extent_.y +
                             std::fabs(d.z) * half_extent_.z);
        const float centre = dot(d, center_);
        if (bounds.upper - (dot(d, bounds.vertex) - centre) <= slack) return bounds.upper;
        const VertexSupport found = vertex_support(bvh, node, d, slack, &bounds.vertex);
        return std::min(bounds.upper, found.value - centre);
    };
    BBox3f box;
    for (int axis = 0; axis < 3; ++axis) {
        const Vec3f row{to_world.col_x[axis], to_world.col_y[axis], to_world.col_z[axis]};
        const float center = dot(row, center_) + to_world.translation[axis];
        box.min[axis] = center - support(-row);
        box.max[axis] = center + support(row);
    }
    // The weights, the sums, the projections and the mapped centre round: 32 ulps.
    return widen_for_mapping_rounding(box, to_world, object_magnitude_, 32.0f);
}

}  // namespace rebraid
