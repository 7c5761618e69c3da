#include "rebraid/bvh/spatial_split.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "rebraid/core/parallel_blocks.h"

namespace rebraid {
namespace {

/// Most bins per axis a spatial split search uses.
constexpr std::uint32_t kMaxSpatialBins = 16;

/// Per axis and bin: the boxes of the parts falling in the bin, and how many references
/// start (entries) and end (exits) in it.
struct SpatialBins {
    std::uint32_t bin_count = 0;
    BBox3f boxes[3][kMaxSpatialBins];
    std::uint32_t entries[3][kMaxSpatialBins] = {};
    std::uint32_t exits[3][kMaxSpatialBins] = {};

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

/// Extends `boxes[b]`, for each bin b from `first` to `last` along `axis`, by the box of the part
/// of `triangle` within `box` in that bin. The part in a slab between two planes is a convex
/// polygon whose corners are the triangle's corners inside the slab and the points where its
/// edges cross the two planes; with the corners sorted along the axis, each plane is crossed
/// by the edge from the lowest to the highest corner and by one of the other two. So each
/// plane costs two points, where chopping the part off bin by bin (split_triangle_box) clipped
/// all three edges again for every bin.
void bin_triangle_parts(const std::array<Vec3f, 3>& triangle, const BBox3f& box,
                        const SpatialSplit& axis, std::uint32_t first, std::uint32_t last,
                        BBox3f* boxes) {
    const int a = axis.axis;
    std::array<Vec3f, 3> sorted = triangle;
    if (sorted[1][a] < sorted[0][a]) std::swap(sorted[0], sorted[1]);
    if (sorted[2][a] < sorted[1][a]) std::swap(sorted[1], sorted[2]);
    if (sorted[1][a] < sorted[0][a]) std::swap(sorted[0], sorted[1]);
    const Vec3f &low = sorted[0], &middle = sorted[1], &high = sorted[2];
    // The crossings carry rounding: widen them by a few ulps of the box's coordinates' size.
    // (These boxes only price the split; the boxes of the parts a split makes come from
    // split_triangle_box.)
    float size = 0.0f;
    for (int i = 0; i < 3; ++i)
        size = std::max({size, std::fabs(box.min[i]), std::fabs(box.max[i])});
    const float slack = 0x1p-21f * size + 0x1p-126f;
    const auto point_on = [&](const Vec3f& from, const Vec3f& to, float plane) {
        const float span = to[a] - from[a];
        const float t = span > 0.0f ? std::clamp((plane - from[a]) / span, 0.0f, 1.0f) : 0.0f;
        Vec3f point = from + (to - from) * t;
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
        if (!part.is_empty()) boxes[b].extend(part);
    }
}

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
                bins.boxes[a][first].extend(ref.bounds);
            else
                bin_triangle_parts(triangle, ref.bounds, axis, first, last, bins.boxes[a]);
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

    SpatialBins bins;
    bins.bin_count = bin_count;
    if (refs.size() < parallel_threshold) {
        bin_references(refs, mesh, layout, bins);
    } else {
        std::vector<SpatialBins> partial(parallel_block_count(refs.size()));
        for_each_block(refs.size(), [&](std::size_t block, std::size_t begin, std::size_t end) {
            partial[block].bin_count = bin_count;
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
            box.extend(bins.boxes[a][b]);
            exits += bins.exits[a][b];
            right_area[b] = box.half_area();
            right_refs[b] = exits;
        }
        box = BBox3f{};
        std::uint32_t entries = 0;
        for (std::uint32_t b = 1; b < bin_count; ++b) {
            box.extend(bins.boxes[a][b - 1]);
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
