#include "rebraid/core/transform.h"

#include <algorithm>
#include <cmath>

namespace rebraid {

AffineTransform AffineTransform::rotate(Vec3f axis, float radians) {
    const float c = std::cos(radians), s = std::sin(radians), k = 1.0f - c;
    const Vec3f a = normalize(axis);
    // Rodrigues' formula, written column by column.
    return {{c + a.x * a.x * k, a.y * a.x * k + a.z * s, a.z * a.x * k - a.y * s},
            {a.x * a.y * k - a.z * s, c + a.y * a.y * k, a.z * a.y * k + a.x * s},
            {a.x * a.z * k + a.y * s, a.y * a.z * k - a.x * s, c + a.z * a.z * k},
            {0.0f, 0.0f, 0.0f}};
}

AffineTransform AffineTransform::inverse() const {
    // Rows of the inverse linear part are the cross products of the columns over det.
    const float inv_det = 1.0f / determinant();
    const Vec3f row_x = cross(col_y, col_z) * inv_det;
    const Vec3f row_y = cross(col_z, col_x) * inv_det;
    const Vec3f row_z = cross(col_x, col_y) * inv_det;
    AffineTransform inv;
    inv.col_x = {row_x.x, row_y.x, row_z.x};
    inv.col_y = {row_x.y, row_y.y, row_z.y};
    inv.col_z = {row_x.z, row_y.z, row_z.z};
    inv.translation = -inv.transform_vector(translation);
    return inv;
}

BBox3f AffineTransform::transform_bbox(const BBox3f& box) const {
    if (box.is_empty()) return box;
    // Per output axis, each column contributes its min or max over the input interval
    // (the box of the 8 transformed corners, computed without enumerating them).
    BBox3f out{translation, translation};
    const Vec3f* cols[3] = {&col_x, &col_y, &col_z};
    for (int in_axis = 0; in_axis < 3; ++in_axis) {
        const Vec3f lo = *cols[in_axis] * box.min[in_axis];
        const Vec3f hi = *cols[in_axis] * box.max[in_axis];
        out.min = out.min + rebraid::min(lo, hi);
        out.max = out.max + rebraid::max(lo, hi);
    }
    return out;
}

BBox3f AffineTransform::transform_bbox_conservative(const BBox3f& box) const {
    BBox3f out = transform_bbox(box);
    if (out.is_empty() || *this == identity()) return out;
    const Vec3f* cols[3] = {&col_x, &col_y, &col_z};
    for (int axis = 0; axis < 3; ++axis) {
        float terms = std::fabs(translation[axis]);
        for (int in_axis = 0; in_axis < 3; ++in_axis)
            terms += std::fabs((*cols[in_axis])[axis]) *
                     std::max(std::fabs(box.min[in_axis]), std::fabs(box.max[in_axis]));
        const float pad = terms * 0x1p-20f;
        out.min[axis] -= pad;
        out.max[axis] += pad;
    }
    return out;
}

AffineTransform operator*(const AffineTransform& a, const AffineTransform& b) {
    return {a.transform_vector(b.col_x), a.transform_vector(b.col_y), a.transform_vector(b.col_z),
            a.transform_point(b.translation)};
}

}  // namespace rebraid
