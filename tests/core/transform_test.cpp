#include "rebraid/core/transform.h"

#include <gtest/gtest.h>

namespace rebraid {
namespace {

void expect_near(Vec3f a, Vec3f b, float tolerance = 1e-5f) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(AffineTransform, InverseUndoesRotationScaleTranslation) {
    const AffineTransform m = AffineTransform::translate({1, -2, 3}) *
                              AffineTransform::rotate({1, 1, 0}, 0.7f) *
                              AffineTransform::scale({2, -0.5f, 3});
    const AffineTransform inv = m.inverse();
    for (Vec3f p : {Vec3f{0, 0, 0}, Vec3f{1, 2, 3}, Vec3f{-5, 0.25f, 9}})
        expect_near(inv.transform_point(m.transform_point(p)), p);
}

TEST(AffineTransform, RotationAboutZTurnsXIntoY) {
    const AffineTransform r = AffineTransform::rotate({0, 0, 1}, 1.5707963f);
    expect_near(r.transform_vector({1, 0, 0}), {0, 1, 0});
}

TEST(AffineTransform, TransformedBoxHoldsEveryTransformedCorner) {
    const AffineTransform m =
        AffineTransform::rotate({0.3f, -1, 2}, 2.1f) * AffineTransform::scale({1, 4, -2});
    const BBox3f box{{-1, 0, 2}, {3, 1, 5}};
    const BBox3f out = m.transform_bbox(box);
    BBox3f corners;
    for (int c = 0; c < 8; ++c) {
        Vec3f p{(c & 1) ? box.max.x : box.min.x, (c & 2) ? box.max.y : box.min.y,
                (c & 4) ? box.max.z : box.min.z};
        corners.extend(m.transform_point(p));
    }
    // The box of the corners is exactly the tightest AABB of the transformed box.
    expect_near(out.min, corners.min, 1e-4f);
    expect_near(out.max, corners.max, 1e-4f);
}

TEST(AffineTransform, MapsBoxesToBoxesOnlyWhenEachAxisGoesToOneAxis) {
    // Scales, mirrors, axis permutations (a quarter turn written with exact zeros) and
    // translations keep a box a box.
    EXPECT_TRUE(AffineTransform::identity().maps_boxes_to_boxes());
    EXPECT_TRUE((AffineTransform::translate({4, -1, 2}) * AffineTransform::scale({2, -3, 0.5f}))
                    .maps_boxes_to_boxes());
    const AffineTransform quarter_turn{{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}, {7, 0, 0}};
    EXPECT_TRUE(quarter_turn.maps_boxes_to_boxes());
    // Any mixing of two axes into one does not: a rotation, a shear, a rounded quarter turn.
    EXPECT_FALSE(AffineTransform::rotate({0, 0, 1}, 0.3f).maps_boxes_to_boxes());
    const AffineTransform shear{{1, 0, 0}, {0.5f, 1, 0}, {0, 0, 1}, {0, 0, 0}};
    EXPECT_FALSE(shear.maps_boxes_to_boxes());
    EXPECT_FALSE(AffineTransform::rotate({0, 0, 1}, 1.5707963f).maps_boxes_to_boxes());
}

TEST(AffineTransform, EmptyBoxStaysEmpty) {
    EXPECT_TRUE(AffineTransform::scale({2, 2, 2}).transform_bbox(BBox3f{}).is_empty());
}

}  // namespace
}  // namespace rebraid
