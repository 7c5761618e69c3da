#include "rebraid/binned_split.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <vector>

namespace rebraid {
namespace {

constexpr std::uint32_t kMaxBins = 256;

std::uint32_t bin_index(float centroid, float origin, float scale, std::uint32_t bin_count) {
    const float position = (centroid - origin) * scale;
    // Clamp in float first: a NaN-free but huge value must not overflow the integer cast.
    const float clamped = std::clamp(position, 0.0f, float(bin_count - 1));
    return std::uint32_t(clamped);
}

/// Per-axis bins of one range: each bin's prim bounds, centroid bounds and weight.
struct Bins {
    std::uint32_t bin_count = 0;
    std::array<std::vector<RangeInfo>, 3> axes;

    explicit Bins(std::uint32_t count) : bin_count(count) {
        for (auto& axis : axes) axis.resize(count);
    }
    void merge(const Bins& other) {
        for (int a = 0; a < 3; ++a)
            for (std::uint32_t b = 0; b < bin_count; ++b) axes[a][b].merge(other.axes[a][b]);
    }
};

}  // namespace

std::uint32_t BinnedSplit::bin_of(const BuildPrim& prim) const {
    return bin_index(prim.centroid()[axis], origin, scale, bin_count);
}

RangeInfo compute_range_info(std::span<const BuildPrim> prims, std::size_t parallel_threshold) {
    auto accumulate = [&](const tbb::blocked_range<std::size_t>& r, RangeInfo info) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) info.add(prims[i]);
        return info;
    };
    if (prims.size() < parallel_threshold) return accumulate({0, prims.size()}, RangeInfo{});
    return tbb::parallel_reduce(tbb::blocked_range<std::size_t>(0, prims.size(), 1024), RangeInfo{},
                                accumulate, [](RangeInfo a, const RangeInfo& b) {
                                    a.merge(b);
                                    return a;
                                });
}

BinnedSplit find_binned_split(std::span<const BuildPrim> prims, const RangeInfo& info,
                              const BuildSettings& settings) {
    const std::uint32_t bin_count = std::min(settings.bin_count, kMaxBins);
    const Vec3f extent = info.centroid_bounds.extent();
    // Bins slightly narrower than extent / bin_count so the largest centroid lands in the
    // last bin rather than one past it.
    Vec3f scale;
    for (int a = 0; a < 3; ++a)
        scale[a] = extent[a] > 0.0f ? (float(bin_count) * 0.99999f) / extent[a] : 0.0f;
    const Vec3f origin = info.centroid_bounds.min;

    auto fill = [&](const tbb::blocked_range<std::size_t>& r, Bins bins) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const BuildPrim& prim = prims[i];
            const Vec3f c = prim.centroid();
            for (int a = 0; a < 3; ++a)
                if (scale[a] > 0.0f)
                    bins.axes[a][bin_index(c[a], origin[a], scale[a], bin_count)].add(prim);
        }
        return bins;
    };
    Bins bins(bin_count);
    if (prims.size() < settings.parallel_threshold) {
        bins = fill({0, prims.size()}, std::move(bins));
    } else {
        bins = tbb::parallel_reduce(tbb::blocked_range<std::size_t>(0, prims.size(), 4096),
                                    Bins(bin_count), fill, [](Bins a, const Bins& b) {
                                        a.merge(b);
                                        return a;
                                    });
    }

    // Sweep each axis: right-to-left prefix of the right side, then left-to-right. Ties keep
    // the first (lowest axis, lowest bin) candidate, so the choice is reproducible.
    BinnedSplit best;
    std::vector<RangeInfo> right_prefix(bin_count);
    for (int a = 0; a < 3; ++a) {
        if (scale[a] <= 0.0f) continue;
        const std::vector<RangeInfo>& axis_bins = bins.axes[a];
        RangeInfo right;
        for (std::uint32_t b = bin_count - 1; b > 0; --b) {
            right.merge(axis_bins[b]);
            right_prefix[b] = right;
        }
        RangeInfo left;
        for (std::uint32_t b = 1; b < bin_count; ++b) {
            left.merge(axis_bins[b - 1]);
            const RangeInfo& r = right_prefix[b];
            if (left.count == 0 || r.count == 0) continue;
            const float cost = left.bounds.half_area() * float(left.weight) +
                               r.bounds.half_area() * float(r.weight);
            if (cost < best.cost) {
                best.axis = a;
                best.bin = b;
                best.cost = cost;
                best.left = left;
                best.right = r;
            }
        }
    }
    if (best.is_valid()) {
        best.origin = origin[best.axis];
        best.scale = scale[best.axis];
        best.bin_count = bin_count;
    }
    return best;
}

}  // namespace rebraid
