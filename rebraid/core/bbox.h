#pragma once

#include <limits>

#include "rebraid/core/types.h"

namespace rebraid {

/// Axis-aligned box. The default is empty (min = +inf, max = -inf), so extending it by
/// anything yields that thing, and an empty box never overlaps a ray.
struct BBox3f {
    Vec3f min{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
              std::numeric_limits<float>::infinity()};
    Vec3f max{-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
              -std::numeric_limits<float>::infinity()};

    bool is_empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    void extend(Vec3f p) {
        min = rebraid::min(min, p);
        max = rebraid::max(max, p);
    }
    void extend(const BBox3f& b) {
        min = rebraid::min(min, b.min);
        max = rebraid::max(max, b.max);
    }
    Vec3f extent() const { return max - min; }
    Vec3f center() const { return (min + max) * 0.5f; }
    /// Half the surface area; 0 for an empty box. SAH only ever needs area ratios.
    float half_area() const {
        if (is_empty()) return 0.0f;
        Vec3f d = extent();
        return d.x * d.y + d.y * d.z + d.z * d.x;
    }
    int largest_axis() const {
        Vec3f d = extent();
        return (d.x >= d.y && d.x >= d.z) ? 0 : (d.y >= d.z ? 1 : 2);
    }
    bool contains(const BBox3f& b) const {
        return b.min.x >= min.x && b.min.y >= min.y && b.min.z >= min.z && b.max.x <= max.x &&
               b.max.y <= max.y && b.max.z <= max.z;
    }
    friend bool operator==(const BBox3f&, const BBox3f&) = default;
};

inline BBox3f merge(BBox3f a, const BBox3f& b) {
    a.extend(b);
    return a;
}

inline BBox3f intersection(const BBox3f& a, const BBox3f& b) {
    return {max(a.min, b.min), min(a.max, b.max)};
}

}  // namespace rebraid
