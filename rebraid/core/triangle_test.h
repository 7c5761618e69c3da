#pragma once

#include <string_view>

namespace rebraid {

/// Which ray-triangle test a structure's traversal runs. Both report t, u (weight of v1) and
/// v (weight of v2) in Embree's convention, and both never hit a degenerate triangle; they
/// differ at edges and vertices and in cost.
enum class TriangleTest {
    /// Möller and Trumbore's test on the triangle's edges from v0, in the form of Embree's
    /// default mode (edges and normal from the corners, the signs of the two edge weights
    /// against the normal's): a ray through an edge shared by two triangles may miss both by
    /// rounding, as in Embree without RTC_SCENE_FLAG_ROBUST. About two thirds of the
    /// watertight test's arithmetic per triangle.
    moller,
    /// Edge functions in Plücker form on origin-relative corners (intersect_triangle in
    /// triangle.h): an edge shared by two triangles gets exactly negated functions in both, so
    /// no ray passes between them, as in Embree's RTC_SCENE_FLAG_ROBUST mode.
    watertight,
};

/// "moller" or "watertight".
constexpr std::string_view triangle_test_name(TriangleTest test) {
    return test == TriangleTest::moller ? "moller" : "watertight";
}

}  // namespace rebraid
