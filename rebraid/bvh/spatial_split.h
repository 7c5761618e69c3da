#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include "rebraid/bvh/build_prim.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// A spatial split of a range of triangle references (Stich, Friedrich and Dietrich, "Spatial
/// Splits in Bounding Volume Hierarchies", HPG 2009): a plane across the range's box, the
/// references wholly on one side going there and those crossing it going to both sides, each
/// side's copy bounded by the part of its triangle on that side. Where triangles are long or
/// slanted, their boxes overlap whatever object split is chosen; cutting them lets the children's
/// boxes stop at the plane.
struct SpatialSplit {
    int axis = -1;               ///< -1: no spatial split found
    std::uint32_t bin = 0;       ///< the plane is bin `bin`'s lower edge
    float origin = 0.0f;         ///< coordinate of bin 0's lower edge along `axis`
    float width = 0.0f;          ///< bin width along `axis`
    float inverse_width = 0.0f;  ///< 1 / width, as the binning multiplied by it
    std::uint32_t bin_count = 0;
    float cost = std::numeric_limits<float>::infinity();  ///< A_L N_L + A_R N_R (half areas)

    bool is_valid() const { return axis >= 0; }
    /// The coordinate of bin `b`'s lower edge.
    float plane_of(std::uint32_t b) const { return origin + float(b) * width; }
    float plane() const { return plane_of(bin); }
    /// The bin a coordinate along `axis` falls in; the binning and the partition both use it,
    /// so they agree on which references cross the plane.
    std::uint32_t bin_of(float coordinate) const {
        float position = (coordinate - origin) * inverse_width;
        position = position > 0.0f ? position : 0.0f;
        const float last = float(bin_count - 1);
        position = position < last ? position : last;
        return std::uint32_t(position);
    }
    /// Whether `box` lies wholly left of the plane (by its bins), wholly right, or crosses it.
    bool is_left_only(const BBox3f& box) const { return bin_of(box.max[axis]) < bin; }
    bool is_right_only(const BBox3f& box) const { return bin_of(box.min[axis]) >= bin; }
};

/// The boxes of the parts of `triangle` within `box` on either side of the plane at
/// `plane` along `axis` (empty where no part lies there). Conservative: each contains the exact
/// part's box, rounding allowed for, and neither leaves `box`.
inline void split_triangle_box(const std::array<Vec3f, 3>& triangle, const BBox3f& box, int axis,
                               float plane, BBox3f& left, BBox3f& right) {
    left = BBox3f{};
    right = BBox3f{};
    bool crossed = false;
    for (int i = 0; i < 3; ++i) {
        const Vec3f& a = triangle[i];
        const Vec3f& b = triangle[i == 2 ? 0 : i + 1];
        const float pa = a[axis], pb = b[axis];
        if (pa <= plane) left.extend(a);
        if (pa >= plane) right.extend(a);
        if ((pa < plane && pb > plane) || (pa > plane && pb < plane)) {
            const Vec3f crossing = a + (b - a) * ((plane - pa) / (pb - pa));
            left.extend(crossing);
            right.extend(crossing);
            crossed = true;
        }
    }
    if (crossed) {
        // The crossings carry rounding: widen both boxes by a few ulps of their coordinates'
        // size (the split axis is set to the plane below), so neither comes out smaller than
        // the exact part's box.
        for (int a = 0; a < 3; ++a) {
            const float slack =
                0x1p-21f * std::max(std::max(std::fabs(left.min[a]), std::fabs(left.max[a])),
                                    std::max(std::fabs(right.min[a]), std::fabs(right.max[a]))) +
                0x1p-126f;
            left.min[a] -= slack, left.max[a] += slack;
            right.min[a] -= slack, right.max[a] += slack;
        }
    }
    // Only the parts within `box`, on their own side of the plane.
    left = intersection(left, box);
    right = intersection(right, box);
    left.max[axis] = std::min(left.max[axis], plane);
    right.min[axis] = std::max(right.min[axis], plane);
    if (left.is_empty()) left = BBox3f{};
    if (right.is_empty()) right = BBox3f{};
}

/// The best spatial split of `refs` (triangle references of `mesh`: BuildPrim::id names the
/// triangle, BuildPrim::bounds the part of it the reference stands for) whose box is `bounds`,
/// binned with `bin_count` bins per axis (2 to 16); only splits that send at least one reference to
/// each side and add at most `max_duplicates` references are considered. Parallel in fixed blocks
/// at or above `parallel_threshold` references; boxes and counts merge exactly, so the result
/// never depends on the thread count.
SpatialSplit find_spatial_split(std::span<const BuildPrim> refs, const BBox3f& bounds,
                                const Mesh& mesh, std::uint32_t bin_count,
                                std::uint32_t max_duplicates, std::size_t parallel_threshold);

}  // namespace rebraid
