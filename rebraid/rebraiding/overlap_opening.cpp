#include "rebraid/rebraiding/overlap_opening.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace rebraid {
namespace {

constexpr int kMaxCellsPerAxis = 8;
constexpr InstanceId kNoInstance = ~InstanceId(0);

/// Cells of a grid over a segment, and which cells a box covers.
class SegmentGrid {
public:
    SegmentGrid(const BBox3f& bounds, std::size_t box_count) : origin_(bounds.min) {
        const int per_axis =
            std::clamp(int(std::ceil(std::cbrt(double(box_count)))), 1, kMaxCellsPerAxis);
        const Vec3f extent = bounds.extent();
        const float largest = std::max({extent.x, extent.y, extent.z});
        for (int a = 0; a < 3; ++a) {
            // Thin axes get fewer cells, so cells stay roughly cubic.
            cells_[a] = largest > 0.0f ? std::clamp(int(std::ceil(per_axis * extent[a] / largest)),
                                                    1, per_axis)
                                       : 1;
            cell_size_[a] = extent[a] / float(cells_[a]);
        }
    }
    std::size_t cell_count() const { return std::size_t(cells_[0]) * cells_[1] * cells_[2]; }
    int cells(int axis) const { return cells_[axis]; }
    int cell_of(float x, int axis) const {
        if (!(cell_size_[axis] > 0.0f)) return 0;
        return std::clamp(int((x - origin_[axis]) / cell_size_[axis]), 0, cells_[axis] - 1);
    }
    /// Fraction of [lo, hi] along `axis` inside cell `c` (1 for a flat box in that cell).
    float fraction_in(float lo, float hi, int axis, int c) const {
        if (!(hi > lo) || !(cell_size_[axis] > 0.0f)) return 1.0f;
        const float cell_lo = origin_[axis] + cell_size_[axis] * float(c);
        const float cell_hi = c + 1 == cells_[axis] ? hi : cell_lo + cell_size_[axis];
        const float low = c == 0 ? lo : std::max(lo, cell_lo);
        return std::max(0.0f, std::min(hi, cell_hi) - low) / (hi - lo);
    }
    std::size_t index(int x, int y, int z) const {
        return (std::size_t(z) * cells_[1] + y) * cells_[0] + x;
    }

private:
    Vec3f origin_;
    std::array<int, 3> cells_{1, 1, 1};
    Vec3f cell_size_;
};

/// Calls visit(cell index, x, y, z) for every cell `box` touches.
template <class Visit>
void for_each_cell(const SegmentGrid& grid, const BBox3f& box, Visit&& visit) {
    std::array<int, 3> lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = grid.cell_of(box.min[a], a);
        hi[a] = grid.cell_of(box.max[a], a);
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y)
            for (int x = lo[0]; x <= hi[0]; ++x) visit(grid.index(x, y, z), x, y, z);
}

}  // namespace

std::vector<std::uint8_t> select_overlapping(std::span<const BuildPrim> prims,
                                             std::span<const BRefTarget> targets,
                                             const BBox3f& segment_bounds, float min_fraction) {
    std::vector<std::uint8_t> selected(prims.size(), 0);
    if (prims.size() < 2) return selected;
    const SegmentGrid grid(segment_bounds, prims.size());
    // Pass 1: per cell, the first instance touching it and whether another one does too.
    // Whether a second instance exists does not depend on the order the BRefs come in.
    std::vector<InstanceId> first_instance(grid.cell_count(), kNoInstance);
    std::vector<std::uint8_t> is_shared(grid.cell_count(), 0);
    for (const BuildPrim& prim : prims) {
        const InstanceId instance = targets[prim.id].instance_id;
        for_each_cell(grid, prim.bounds, [&](std::size_t cell, int, int, int) {
            if (first_instance[cell] == kNoInstance)
                first_instance[cell] = instance;
            else if (first_instance[cell] != instance)
                is_shared[cell] = 1;
        });
    }
    // Pass 2: the share of each box in shared cells.
    for (std::size_t i = 0; i < prims.size(); ++i) {
        const BBox3f& box = prims[i].bounds;
        float shared = 0.0f;
        for_each_cell(grid, box, [&](std::size_t cell, int x, int y, int z) {
            if (!is_shared[cell]) return;
            shared += grid.fraction_in(box.min.x, box.max.x, 0, x) *
                      grid.fraction_in(box.min.y, box.max.y, 1, y) *
                      grid.fraction_in(box.min.z, box.max.z, 2, z);
        });
        selected[i] = shared >= min_fraction;
    }
    return selected;
}

}  // namespace rebraid
