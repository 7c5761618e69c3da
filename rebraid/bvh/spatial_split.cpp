#include "rebraid/bvh/spatial_split.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "rebraid/bvh/build_box.h"
#include "rebraid/core/parallel_blocks.h"

namespace rebraid {
namespace {

/// Most bins per axis a spatial split search uses.
constexpr std::uint32_t kMaxSpatialBins = 16;

/// Per axis and bin: the boxes of the parts falling in the bin, and how many references
/// start (entries) and end (exits) in it. The boxes are BuildBoxes, whose extension is one
/// instruction with AVX: binning the parts is bound by these updates.
struct SpatialBins {
    std::uint32_t bin_count = 0;
    BuildBox boxes[3][kMaxSpatialBins];
    std::uint32_t entries[3][kMaxSpatialBins] = {};
    std::uint32_t exits[3][kMaxSpatialBins] = {};

    explicit SpatialBins(std::uint32_t count) : bin_count(count) {
        for (auto& axis : boxes)
            for (BuildBox& box : axis) box = BuildBox::empty();
    }
    void merge(const SpatialBins& other) {
        for (int a = 0; a < 3; ++a)
            for (std::uint32_t b = 0; b < bin_count; ++b) {
                boxes[a][b].extend(other.boxes[a][b]);
                entries[a][b] += other.entries[a][b];
                exits[a][b] += other.exits[a][b];
            }
    }
};

/// How the bins of each axis are laid out over the range's box: origin, width and inverse
/// width per axis (axis -1: not binned).
using SpatialBinLayout = std::array<SpatialSplit, 3>;

/// The corners of `triangle` sorted along `axis`.
std::array<Vec3f, 3> sorted_along(const std::array<Vec3f, 3>& triangle, int axis) {
    std::array<Vec3f, 3> sorted = triangle;
    if (sorted[1][axis] < sorted[0][axis]) std::swap(sorted[0], sorted[1]);
    if (sorted[2][axis] < sorted[1][axis]) std::swap(sorted[1], sorted[2]);
    if (sorted[1][axis] < sorted[0][axis]) std::swap(sorted[0], sorted[1]);
    return sorted;
}

/// How far a plane's crossings are widened: their rounding, a few ulps of the size of the
/// reference box's coordinates. (These boxes only price the split; the boxes of the parts a
/// split makes come from split_triangle_box.)
float crossing_slack(const BBox3f& box) {
    float size = 0.0f;
    for (int i = 0; i < 3; ++i)
        size = std::max({size, std::fabs(box.min[i]), std::fabs(box.max[i])});
    return 0x1p-21f * size + 0x1p-126f;
}

/// Where the edge from `from` to `to` (`from` not above `to` along the axis) meets the plane
/// at `plane`, as a share of the edge, clamped to it.
inline float crossing_share(float from, float to, float plane) {
    const float span = to - from;
    return span > 0.0f ? std::clamp((plane - from) / span, 0.0f, 1.0f) : 0.0f;
}

// bin_triangle_parts extends `boxes[b]`, for each bin b from `first` to `last` along `axis`,
// by the box of the part of `ref`'s triangle within `ref`'s box in that bin. The part in a
// slab between two planes is a convex polygon whose corners are the triangle's corners inside
// the slab and the points where its edges cross the two planes; with the corners sorted along
// the axis, each plane is crossed by the edge from the lowest to the highest corner and by one
// of the other two. So each plane costs two points, where chopping the part off bin by bin
// (split_triangle_box) clipped all three edges again for every bin.
#if defined(__AVX__)
// With AVX the points and boxes are vectors, each box a BuildBox {min, -max}: a part's box
// is a few min and max instructions where three-float code took a dozen scalar ones each,
// with the same operations per coordinate.
void bin_triangle_parts(const std::array<Vec3f, 3>& triangle, const BuildPrim& ref,
                        const SpatialSplit& axis, std::uint32_t first, std::uint32_t last,
                        BuildBox* boxes) {
    const int a = axis.axis;
    const std::array<Vec3f, 3> sorted = sorted_along(triangle, a);
    const auto vector_of = [](const Vec3f& v) { return _mm_setr_ps(v.x, v.y, v.z, 0.0f); };
    const __m128 low = vector_of(sorted[0]), middle = vector_of(sorted[1]),
                 high = vector_of(sorted[2]);
    const float low_a = sorted[0][a], middle_a = sorted[1][a], high_a = sorted[2][a];
    const __m128 on_axis =
        _mm_castsi128_ps(_mm_setr_epi32(a == 0 ? -1 : 0, a == 1 ? -1 : 0, a == 2 ? -1 : 0, 0));
    const float slack = crossing_slack(ref.bounds);
    // The slack off the axis (the crossings lie on the plane along it); 0 in the spare lane.
    const __m128 widen = _mm_andnot_ps(on_axis, _mm_setr_ps(slack, slack, slack, 0.0f));
    const auto point_on = [&](__m128 from, float from_a, __m128 to, float to_a, float plane) {
        const __m128 t = _mm_set1_ps(crossing_share(from_a, to_a, plane));
        const __m128 point = _mm_add_ps(from, _mm_mul_ps(_mm_sub_ps(to, from), t));
        return _mm_blendv_ps(point, _mm_set1_ps(plane), on_axis);
    };
    // The box of a plane's two crossings, widened.
    const auto crossings = [&](float plane) {
        const __m128 long_edge = point_on(low, low_a, high, high_a, plane);
        const __m128 short_edge = plane < middle_a
                                      ? point_on(low, low_a, middle, middle_a, plane)
                                      : point_on(middle, middle_a, high, high_a, plane);
        BuildBox crossed = BuildBox::point(_mm_sub_ps(_mm_min_ps(long_edge, short_edge), widen));
        crossed.extend_point(_mm_add_ps(_mm_max_ps(long_edge, short_edge), widen));
        return crossed;
    };
    const __m256 within_ref = BuildBox::of(ref).lanes;
    const float infinity = std::numeric_limits<float>::infinity();
    BuildBox lower = BuildBox::empty();  // the crossings of the bin's lower plane
    for (std::uint32_t b = first; b <= last; ++b) {
        BuildBox part = lower;
        const float bottom = b == first ? -infinity : axis.plane_of(b);
        const float top = b == last ? infinity : axis.plane_of(b + 1);
        if (b < last) {
            lower = crossings(top);
            part.extend(lower);
        }
        if (low_a >= bottom && low_a <= top) part.extend_point(low);
        if (middle_a >= bottom && middle_a <= top) part.extend_point(middle);
        if (high_a >= bottom && high_a <= top) part.extend_point(high);
        // Within the reference's box and the slab: {min, -max} lanes raised to {bottom, -top}
        // on the axis and to the box's elsewhere.
        const __m128 slab = _mm_blendv_ps(_mm_set1_ps(-infinity), _mm_set1_ps(bottom), on_axis);
        const __m128 negated_top =
            _mm_blendv_ps(_mm_set1_ps(-infinity), _mm_set1_ps(-top), on_axis);
        part.lanes = _mm256_max_ps(_mm256_max_ps(part.lanes, within_ref),
                                   _mm256_set_m128(negated_top, slab));
        if (!part.is_empty_on_any_axis()) boxes[b].extend(part);
    }
}
#else
void bin_triangle_parts(const std::array<Vec3f, 3>& triangle, const BuildPrim& ref,
                        const SpatialSplit& axis, std::uint32_t first, std::uint32_t last,
                        BuildBox* boxes) {
    const int a = axis.axis;
    const std::array<Vec3f, 3> sorted = sorted_along(triangle, a);
    const Vec3f &low = sorted[0], &middle = sorted[1], &high = sorted[2];
    const BBox3f& box = ref.bounds;
    const float slack = crossing_slack(box);
    const auto point_on = [&](const Vec3f& from, const Vec3f& to, float plane) {
        Vec3f point = from + (to - from) * crossing_share(from[a], to[a], plane);
        point[a] = plane;
        return point;
    };
    // The box of a plane's two crossings, widened.
    const auto crossings = [&](float plane) {
        BBox3f crossed;
        crossed.extend(point_on(low, high, plane));
        crossed.extend(plane < middle[a] ? point_on(low, middle, plane)
                                         : point_on(middle, high, plane));
        for (int i = 0; i < 3; ++i) {
            if (i == a) continue;
            crossed.min[i] -= slack;
            crossed.max[i] += slack;
        }
        return crossed;
    };
    BBox3f lower;  // the crossings of the bin's lower plane (none for the first bin)
    for (std::uint32_t b = first; b <= last; ++b) {
        BBox3f part = lower;
        const float bottom =
            b == first ? -std::numeric_limits<float>::infinity() : axis.plane_of(b);
        const float top = b == last ? std::numeric_limits<float>::infinity() : axis.plane_of(b + 1);
        if (b < last) {
            lower = crossings(top);
            part.extend(lower);
        }
        for (const Vec3f& corner : sorted)
            if (corner[a] >= bottom && corner[a] <= top) part.extend(corner);
        part = intersection(part, box);
        part.min[a] = std::max(part.min[a], bottom);
        part.max[a] = std::min(part.max[a], top);
        if (!part.is_empty()) boxes[b].extend(BuildBox{part});
    }
}
#endif

void bin_references(std::span<const BuildPrim> refs, const Mesh& mesh,
                    const SpatialBinLayout& layout, SpatialBins& bins) {
    for (const BuildPrim& ref : refs) {
        const std::array<Vec3f, 3> triangle = mesh.corners(PrimId(ref.id));
        for (int a = 0; a < 3; ++a) {
            const SpatialSplit& axis = layout[a];
            if (axis.axis < 0) continue;
            const std::uint32_t first = axis.bin_of(ref.bounds.min[a]);
            const std::uint32_t last = axis.bin_of(ref.bounds.max[a]);
            ++bins.entries[a][first];
            ++bins.exits[a][last];
            if (first == last)
                bins.boxes[a][first].extend(BuildBox::of(ref));
            else
                bin_triangle_parts(triangle, ref, axis, first, last, bins.boxes[a]);
        }
    }
}

}  // namespace

SpatialSplit find_spatial_split(std::span<const BuildPrim> refs, const BBox3f& bounds,
                                const Mesh& mesh, std::uint32_t bin_count,
                                std::uint32_t max_duplicates, std::size_t parallel_threshold) {
    SpatialSplit best;
    bin_count = std::clamp(bin_count, 2u, kMaxSpatialBins);
    if (refs.size() < 2) return best;
    SpatialBinLayout layout;
    bool any_axis = false;
    for (int a = 0; a < 3; ++a) {
        const float extent = bounds.max[a] - bounds.min[a];
        SpatialSplit& axis = layout[a];
        if (!(extent > 0.0f) || !std::isfinite(extent)) continue;
        axis.axis = a;
        axis.origin = bounds.min[a];
        axis.width = extent / float(bin_count);
        axis.inverse_width = float(bin_count) / extent;
        axis.bin_count = bin_count;
        // A plane that rounding puts on the box's own edge splits nothing.
        if (!(axis.width > 0.0f) || !std::isfinite(axis.inverse_width)) {
            axis.axis = -1;
            continue;
        }
        any_axis = true;
    }
    if (!any_axis) return best;

    SpatialBins bins(bin_count);
    if (refs.size() < parallel_threshold) {
        bin_references(refs, mesh, layout, bins);
    } else {
        std::vector<SpatialBins> partial(parallel_block_count(refs.size()), bins);
        for_each_block(refs.size(), [&](std::size_t block, std::size_t begin, std::size_t end) {
            bin_references(refs.subspan(begin, end - begin), mesh, layout, partial[block]);
        });
        for (const SpatialBins& part : partial) bins.merge(part);
    }

    const auto count = std::uint32_t(refs.size());
    for (int a = 0; a < 3; ++a) {
        if (layout[a].axis < 0) continue;
        // Sweep from the right: the box and reference count of bins [b, bin_count).
        float right_area[kMaxSpatialBins];
        std::uint32_t right_refs[kMaxSpatialBins];
        BBox3f box;
        std::uint32_t exits = 0;
        for (std::uint32_t b = bin_count; b-- > 1;) {
            box.extend(bins.boxes[a][b].to_bbox());
            exits += bins.exits[a][b];
            right_area[b] = box.half_area();
            right_refs[b] = exits;
        }
        box = BBox3f{};
        std::uint32_t entries = 0;
        for (std::uint32_t b = 1; b < bin_count; ++b) {
            box.extend(bins.boxes[a][b - 1].to_bbox());
            entries += bins.entries[a][b - 1];
            const std::uint32_t left_refs = entries;
            if (left_refs == 0 || right_refs[b] == 0) continue;
            if (left_refs + right_refs[b] > count + max_duplicates) continue;
            const float cost =
                box.half_area() * float(left_refs) + right_area[b] * float(right_refs[b]);
            if (cost < best.cost) {
                best = layout[a];
                best.bin = b;
                best.cost = cost;
            }
        }
    }
    return best;
}

}  // namespace rebraid
