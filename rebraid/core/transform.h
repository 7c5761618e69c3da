#pragma once

#include "rebraid/core/bbox.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// 3x4 affine map p' = L p + t, stored as the three columns of L and the translation, the
/// layout Embree calls RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR.
struct AffineTransform {
    Vec3f col_x{1.0f, 0.0f, 0.0f};
    Vec3f col_y{0.0f, 1.0f, 0.0f};
    Vec3f col_z{0.0f, 0.0f, 1.0f};
    Vec3f translation{0.0f, 0.0f, 0.0f};

    static AffineTransform identity() { return {}; }
    static AffineTransform translate(Vec3f t) { return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, t}; }
    static AffineTransform scale(Vec3f s) {
        return {{s.x, 0, 0}, {0, s.y, 0}, {0, 0, s.z}, {0, 0, 0}};
    }
    /// Rotation by `radians` about the unit `axis` (right-handed).
    static AffineTransform rotate(Vec3f axis, float radians);

    Vec3f transform_vector(Vec3f v) const { return col_x * v.x + col_y * v.y + col_z * v.z; }
    Vec3f transform_point(Vec3f p) const { return transform_vector(p) + translation; }
    float determinant() const { return dot(col_x, cross(col_y, col_z)); }
    bool is_finite() const {
        return rebraid::is_finite(col_x) && rebraid::is_finite(col_y) &&
               rebraid::is_finite(col_z) && rebraid::is_finite(translation);
    }
    /// True when each world axis is a multiple of at most one object axis (scales, mirrors,
    /// axis permutations and translations): the map then takes a box's faces to faces, and
    /// the transformed box of the tight box of some points is the tight box of the mapped
    /// points.
    bool maps_boxes_to_boxes() const {
        for (int axis = 0; axis < 3; ++axis) {
            const int terms =
                int(col_x[axis] != 0.0f) + int(col_y[axis] != 0.0f) + int(col_z[axis] != 0.0f);
            if (terms > 1) return false;
        }
        return true;
    }
    /// Inverse map; the caller checks invertibility (determinant far from 0) first.
    AffineTransform inverse() const;
    /// The smallest AABB holding the transformed box (conservative: the box of the image of
    /// the box, paper §5.4). An empty box stays empty.
    BBox3f transform_bbox(const BBox3f& box) const;
    /// transform_bbox widened so that it holds every point of `box` as transform_point()
    /// rounds it (the two sum their terms in different orders): by 8 ulps of the largest sum
    /// of absolute terms per axis. The identity maps exactly and widens nothing. For the
    /// boxes of structures, whose box tests must never cull a point the object-space test
    /// finds.
    BBox3f transform_bbox_conservative(const BBox3f& box) const;
    friend bool operator==(const AffineTransform&, const AffineTransform&) = default;
};

/// a * b: first b, then a.
AffineTransform operator*(const AffineTransform& a, const AffineTransform& b);

}  // namespace rebraid
