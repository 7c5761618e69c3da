#include "rebraid/bvh/spatial_split_bvh_builder.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/optimal_wide_tree_grower.h"
#include "rebraid/bvh/spatial_split.h"
#include "rebraid/core/error.h"
#include "rebraid/core/parallel_blocks.h"
#include "rebraid/core/scratch_buffer.h"

namespace rebraid {
namespace {

/// Ranges of fewer references look for object splits only: a spatial split of three or fewer
/// triangles hardly pays for its clipping.
constexpr std::uint32_t kMinSpatialSplitRefs = 4;

/// Once this many spatial split searches in a row on the way down found none cheaper than the
/// object split, the ranges below search no more. Where splits pay, they pay near the root and
/// keep paying along the way (long triangles are long at every level); where they do not
/// (meshes of small, evenly sized triangles, whose halves overlap because the surface curves),
/// almost every search comes up empty all the way down. The drop-in's 576 torus knots: 372,125
/// searches found 41 cheaper splits, and stopping after 4 empty ones in a row builds them in
/// 1.12 s instead of 2.04, at an SAH 0.002 % higher; two_cylinder_engine's glue structure in
/// 67 ms instead of 73 (+0.05 %); 3 in a row cost brainstem's flat BVH 0.7 % of SAH, 4 cost
/// 0.1 % (docs/design.md, "Spatial splits").
constexpr std::uint32_t kMaxFruitlessSearches = 4;

/// Bins per axis of the spatial split search: up to 16, one per 4 references in smaller
/// ranges (at least 4), whose triangles would otherwise cross many narrow bins each.
constexpr std::uint32_t kSpatialBins = 16;
constexpr std::uint32_t kRefsPerSpatialBin = 4;

/// A range of references [begin, end) with room for more up to capacity_end, considered as
/// one child of the node being built, with its best split.
struct SegmentCandidate {
    std::uint32_t begin = 0, end = 0, capacity_end = 0;
    RangeInfo info;
    float half_area = 0.0f;
    BinnedSplit split;
    SpatialSplit spatial;
    bool is_spatial = false;  ///< the spatial split is the cheaper one
    bool is_leaf = true;
    bool in_scratch = false;  ///< which of the two buffers holds the references
    /// Spatial split searches in a row on the way down to this range, its own included, that
    /// found none cheaper than the object split (kMaxFruitlessSearches); its halves start from
    /// this count.
    std::uint32_t fruitless_searches = 0;
    std::uint32_t size() const { return end - begin; }
    std::uint32_t room() const { return capacity_end - end; }
    float area() const { return half_area; }
    BBox3f bounds() const { return info.bounds; }
};

/// SpatialSplitSearchCounts, one per thread of the build, summed when it ends: counters
/// shared by every task would move their cache line between the cores at every range.
using ThreadSearchCounts = tbb::enumerable_thread_specific<SpatialSplitSearchCounts>;

class SpatialSplitBvhBuilder {
public:
    SpatialSplitBvhBuilder(const Mesh& mesh, std::span<BuildPrim> refs,
                           std::span<BuildPrim> scratch, const BuildSettings& settings,
                           std::span<const std::uint32_t> leaf_groups, ThreadSearchCounts& counts)
        : mesh_(mesh),
          refs_(refs),
          scratch_(scratch),
          settings_(settings),
          leaf_groups_(leaf_groups),
          counts_(&counts) {}

    /// The root's half area, against which overlaps are weighed.
    void set_root_area(float half_area) { root_area_ = half_area; }

    SegmentCandidate evaluate(std::uint32_t begin, std::uint32_t end, std::uint32_t capacity_end,
                              bool in_scratch, const RangeInfo& info, bool median_only,
                              std::uint32_t fruitless_searches) const {
        SegmentCandidate c;
        c.begin = begin, c.end = end, c.capacity_end = capacity_end;
        c.info = info;
        c.half_area = info.bounds.half_area();
        c.in_scratch = in_scratch;
        c.fruitless_searches = fruitless_searches;
        const std::uint32_t n = c.size();
        if (n <= 1) return c;
        if (!median_only) {
            c.split = find_binned_split(range(c), info, settings_);
            if (c.room() > 0 && n >= kMinSpatialSplitRefs) {
                ++counts_->local().candidates;
                if (fruitless_searches < kMaxFruitlessSearches && overlaps_much(c))
                    search_spatial_split(c, fruitless_searches);
            }
        }
        if (!c.split.is_valid() && !c.is_spatial) {
            c.is_leaf = n <= settings_.max_leaf_size && !mixes_groups(c);
            return c;
        }
        const float children_cost = c.is_spatial ? c.spatial.cost : c.split.cost;
        const float leaf_cost = settings_.intersection_cost * c.half_area * float(info.weight);
        const float split_cost =
            settings_.traversal_cost * c.half_area + settings_.intersection_cost * children_cost;
        c.is_leaf = n <= settings_.max_leaf_size && leaf_cost <= split_cost && !mixes_groups(c);
        return c;
    }

    std::array<SegmentCandidate, 2> split(const SegmentCandidate& c, bool median_only) const {
        if (c.is_spatial) {
            std::array<SegmentCandidate, 2> halves;
            if (split_spatially(c, median_only, halves)) return halves;
        }
        SplitResult s;
        bool in_scratch = c.in_scratch;
        if (c.split.is_valid()) {
            bool moved = false;
            s = apply_split_in_or_across(range(c), range(c.begin, c.end, !c.in_scratch), c.split,
                                         settings_.parallel_threshold, moved);
            if (moved) in_scratch = !c.in_scratch;
        }
        if (s.left_count > 0 && s.left_count < c.size())
            return halves_of(c, in_scratch, s.left_count, s.left, s.right, median_only);
        const std::uint32_t half = c.size() / 2;
        const std::size_t threshold = settings_.parallel_threshold;
        const RangeInfo left =
            compute_range_info(range(c.begin, c.begin + half, in_scratch), threshold);
        const RangeInfo right =
            compute_range_info(range(c.begin + half, c.end, in_scratch), threshold);
        return halves_of(c, in_scratch, half, left, right, median_only);
    }

    NodeRef make_leaf(const SegmentCandidate& c) const {
        if (c.in_scratch) {
            const std::span<const BuildPrim> from = range(c);
            std::copy(from.begin(), from.end(), refs_.begin() + c.begin);
        }
        return NodeRef::leaf(c.begin, c.size());
    }

private:
    /// Whether the references of `c` belong to more than one leaf group (never when the build
    /// has none). Asked of ranges small enough to be leaves only.
    bool mixes_groups(const SegmentCandidate& c) const {
        if (leaf_groups_.empty()) return false;
        const std::span<BuildPrim> refs = range(c);
        return std::any_of(refs.begin(), refs.end(), [&](const BuildPrim& ref) {
            return leaf_groups_[ref.id] != leaf_groups_[refs.front().id];
        });
    }

    /// Weighs the best spatial split of `c` (with room and at least kMinSpatialSplitRefs
    /// references) against its object split, and counts the search.
    void search_spatial_split(SegmentCandidate& c, std::uint32_t fruitless_searches) const {
        const std::uint32_t bins = std::clamp(c.size() / kRefsPerSpatialBin, 4u, kSpatialBins);
        c.spatial = find_spatial_split(range(c), c.info.bounds, mesh_, bins, c.room(),
                                       settings_.parallel_threshold);
        c.is_spatial = c.spatial.is_valid() && c.spatial.cost < c.split.cost;
        c.fruitless_searches = c.is_spatial ? 0 : fruitless_searches + 1;
        SpatialSplitSearchCounts& counts = counts_->local();
        ++counts.searches;
        if (c.is_spatial) ++counts.cheaper;
        counts.longest_fruitless_run = std::max(counts.longest_fruitless_run, c.fruitless_searches);
    }

    /// Whether the boxes of the object split's halves overlap by more than a small share of
    /// the root's area (the criterion of Stich et al. 2009): only then can a spatial split be worth
    /// its search, which clips every crossing triangle. The paper's share is 1e-5; 1e-3 built
    /// two_cylinder_engine and cg57_cruiser in half the time for an SAH within 0.1 and 0.6 %
    /// of it, and the drop-in's flattened grid (whose ground quad every lower split would cut
    /// again) in two thirds, at a lower SAH (docs/design.md, "Spatial splits").
    bool overlaps_much(const SegmentCandidate& c) const {
        if (!c.split.is_valid()) return true;
        struct Sides {
            BBox3f left, right;
        };
        const std::span<const BuildPrim> refs = range(c);
        const Sides sides = reduce_over_blocks(
            refs.size(), settings_.parallel_threshold, Sides{},
            [&](std::size_t begin, std::size_t end, Sides sides) {
                for (const BuildPrim& ref : refs.subspan(begin, end - begin))
                    (c.split.goes_left(ref) ? sides.left : sides.right).extend(ref.bounds);
                return sides;
            },
            [](Sides a, const Sides& b) {
                a.left.extend(b.left);
                a.right.extend(b.right);
                return a;
            });
        return intersection(sides.left, sides.right).half_area() > kOverlapShare * root_area_;
    }

    /// The two halves of `c` once its references are divided: the first `left_count` of them
    /// (in the buffer `in_scratch` names) go left, the rest right. The room beyond them is
    /// shared in proportion to the counts, the right half's references moved up to start
    /// their segment.
    std::array<SegmentCandidate, 2> halves_of(const SegmentCandidate& c, bool in_scratch,
                                              std::uint32_t left_count, const RangeInfo& left,
                                              const RangeInfo& right, bool median_only) const {
        const std::uint32_t right_count = c.size() - left_count;
        const std::uint32_t left_room = share_of_room(c.room(), left_count, right_count);
        const std::uint32_t right_begin = c.begin + left_count + left_room;
        if (left_room > 0) {
            const std::span<BuildPrim> buffer = in_scratch ? scratch_ : refs_;
            std::copy_backward(buffer.begin() + c.begin + left_count, buffer.begin() + c.end,
                               buffer.begin() + right_begin + right_count);
        }
        return {evaluate(c.begin, c.begin + left_count, right_begin, in_scratch, left, median_only,
                         c.fruitless_searches),
                evaluate(right_begin, right_begin + right_count, c.capacity_end, in_scratch, right,
                         median_only, c.fruitless_searches)};
    }

    /// Room for the left half: `room` split in proportion to the halves' counts, rounded down.
    static std::uint32_t share_of_room(std::uint32_t room, std::uint32_t left_count,
                                       std::uint32_t right_count) {
        return std::uint32_t(std::uint64_t(room) * left_count / (left_count + right_count));
    }

    /// Hands `ref` to the side(s) of `split` it lies on: `put_left(part)`, `put_right(part)`;
    /// a reference crossing the plane is cut, each part boxed by split_triangle_box (both parts
    /// empty cannot happen, but then the whole reference goes left).
    template <class PutLeft, class PutRight>
    void divide(const SpatialSplit& split, const BuildPrim& ref, PutLeft&& put_left,
                PutRight&& put_right) const {
        if (split.is_left_only(ref.bounds)) return put_left(ref);
        if (split.is_right_only(ref.bounds)) return put_right(ref);
        BBox3f left_box, right_box;
        split_triangle_box(mesh_.corners(PrimId(ref.id)), ref.bounds, split.axis, split.plane(),
                           left_box, right_box);
        if (left_box.is_empty() && right_box.is_empty()) left_box = ref.bounds;
        if (!left_box.is_empty()) put_left({left_box, ref.id, ref.weight});
        if (!right_box.is_empty()) put_right({right_box, ref.id, ref.weight});
    }

    /// Divides `c` by its spatial split into the other buffer: left references from the
    /// segment's start up, right ones from its end down (large ranges in parallel blocks,
    /// split_spatially_in_blocks). False (the source untouched) when a side came out empty or
    /// the references outgrew the room.
    bool split_spatially(const SegmentCandidate& c, bool median_only,
                         std::array<SegmentCandidate, 2>& halves) const {
        const std::span<const BuildPrim> from = range(c);
        if (from.size() >= settings_.parallel_threshold)
            return split_spatially_in_blocks(c, median_only, halves);
        const bool in_scratch = !c.in_scratch;
        const std::span<BuildPrim> to = range(c.begin, c.capacity_end, in_scratch);
        std::uint32_t left_count = 0, right_count = 0;
        RangeInfo left, right;
        // The binning counted every side a reference goes to, and the room was checked
        // against those counts; a part that finds no slot would mean they disagree.
        bool outgrew = false;
        const auto has_room = [&] {
            outgrew = outgrew || left_count + right_count >= to.size();
            return !outgrew;
        };
        for (const BuildPrim& ref : from)
            divide(
                c.spatial, ref,
                [&](const BuildPrim& part) {
                    if (!has_room()) return;
                    to[left_count++] = part;
                    left.add(part);
                },
                [&](const BuildPrim& part) {
                    if (!has_room()) return;
                    to[to.size() - 1 - right_count++] = part;
                    right.add(part);
                });
        if (outgrew || left_count == 0 || right_count == 0) return false;
        // The right references, stored from the end down, move to follow the left ones' room.
        const std::uint32_t room = c.capacity_end - c.begin - left_count - right_count;
        const std::uint32_t left_room = share_of_room(room, left_count, right_count);
        const std::uint32_t right_begin = left_count + left_room;
        std::copy(to.end() - right_count, to.end(), to.begin() + right_begin);
        halves = {evaluate(c.begin, c.begin + left_count, c.begin + right_begin, in_scratch, left,
                           median_only, c.fruitless_searches),
                  evaluate(c.begin + right_begin, c.begin + right_begin + right_count,
                           c.capacity_end, in_scratch, right, median_only, c.fruitless_searches)};
        return true;
    }

    /// split_spatially for large ranges: each block of references (parallel_blocks.h) divided
    /// into lists of its own in parallel, the lists then copied out in block order (so the
    /// order depends on the input and the threshold only), left ones first, right ones after
    /// the left ones' room.
    bool split_spatially_in_blocks(const SegmentCandidate& c, bool median_only,
                                   std::array<SegmentCandidate, 2>& halves) const {
        const std::span<const BuildPrim> from = range(c);
        struct Side {
            std::vector<BuildPrim> refs;
            RangeInfo info;
            void put(const BuildPrim& ref) {
                refs.push_back(ref);
                info.add(ref);
            }
        };
        struct Sides {
            Side left, right;
        };
        std::vector<Sides> blocks(parallel_block_count(from.size()));
        for_each_block(from.size(), [&](std::size_t b, std::size_t begin, std::size_t end) {
            Sides& sides = blocks[b];
            for (const BuildPrim& ref : from.subspan(begin, end - begin))
                divide(
                    c.spatial, ref, [&](const BuildPrim& part) { sides.left.put(part); },
                    [&](const BuildPrim& part) { sides.right.put(part); });
        });
        std::uint64_t left_count = 0, right_count = 0;
        RangeInfo left, right;
        for (const Sides& sides : blocks) {
            left_count += sides.left.refs.size();
            right_count += sides.right.refs.size();
            left.merge(sides.left.info);
            right.merge(sides.right.info);
        }
        const std::uint64_t capacity = c.capacity_end - c.begin;
        if (left_count == 0 || right_count == 0 || left_count + right_count > capacity)
            return false;
        const auto room = std::uint32_t(capacity - left_count - right_count);
        const std::uint32_t left_room =
            share_of_room(room, std::uint32_t(left_count), std::uint32_t(right_count));
        const std::uint32_t right_begin = c.begin + std::uint32_t(left_count) + left_room;
        const bool in_scratch = !c.in_scratch;
        const std::span<BuildPrim> to = in_scratch ? scratch_ : refs_;
        std::vector<std::uint32_t> left_at(blocks.size()), right_at(blocks.size());
        std::uint32_t next_left = c.begin, next_right = right_begin;
        for (std::size_t b = 0; b < blocks.size(); ++b) {
            left_at[b] = next_left;
            right_at[b] = next_right;
            next_left += std::uint32_t(blocks[b].left.refs.size());
            next_right += std::uint32_t(blocks[b].right.refs.size());
        }
        for_each_block(from.size(), [&](std::size_t b, std::size_t, std::size_t) {
            std::copy(blocks[b].left.refs.begin(), blocks[b].left.refs.end(),
                      to.begin() + left_at[b]);
            std::copy(blocks[b].right.refs.begin(), blocks[b].right.refs.end(),
                      to.begin() + right_at[b]);
        });
        halves = {evaluate(c.begin, c.begin + std::uint32_t(left_count), right_begin, in_scratch,
                           left, median_only, c.fruitless_searches),
                  evaluate(right_begin, right_begin + std::uint32_t(right_count), c.capacity_end,
                           in_scratch, right, median_only, c.fruitless_searches)};
        return true;
    }

    std::span<BuildPrim> range(const SegmentCandidate& c) const {
        return range(c.begin, c.end, c.in_scratch);
    }
    std::span<BuildPrim> range(std::uint32_t begin, std::uint32_t end, bool in_scratch) const {
        return (in_scratch ? scratch_ : refs_).subspan(begin, end - begin);
    }

    static constexpr float kOverlapShare = 1e-3f;

    const Mesh& mesh_;
    float root_area_ = 0.0f;
    std::span<BuildPrim> refs_;
    std::span<BuildPrim> scratch_;
    const BuildSettings& settings_;
    std::span<const std::uint32_t> leaf_groups_;  ///< per triangle; empty: none
    ThreadSearchCounts* counts_;
};

/// Closes the gaps the segments' unused room left between leaves: leaves renumbered in the
/// order of their first reference (the tree's left-to-right order), their primIDs listed.
std::vector<PrimId> compact_leaves(WideBvh& tree, std::span<const BuildPrim> refs) {
    struct LeafSlot {
        NodeRef* ref;
        std::uint32_t first;
    };
    std::vector<LeafSlot> leaves;
    if (tree.root.is_leaf()) leaves.push_back({&tree.root, tree.root.first_prim()});
    for (WideNode& node : tree.nodes)
        for (NodeRef& child : node.children)
            if (child.is_leaf()) leaves.push_back({&child, child.first_prim()});
    std::sort(leaves.begin(), leaves.end(),
              [](const LeafSlot& a, const LeafSlot& b) { return a.first < b.first; });
    std::vector<PrimId> leaf_prims;
    for (const LeafSlot& leaf : leaves) {
        const std::uint32_t count = leaf.ref->prim_count();
        const auto first = std::uint32_t(leaf_prims.size());
        for (std::uint32_t i = 0; i < count; ++i) leaf_prims.push_back(refs[leaf.first + i].id);
        *leaf.ref = NodeRef::leaf(first, count);
    }
    return leaf_prims;
}

}  // namespace

SpatialSplitBvh build_spatial_split_bvh(const Mesh& mesh, const BuildSettings& settings,
                                        std::span<const std::uint32_t> leaf_groups) {
    settings.validate();
    if (settings.collapse != NodeCollapse::optimal)
        throw Error("build_spatial_split_bvh: needs the optimal node collapse");
    if (!leaf_groups.empty() && leaf_groups.size() != mesh.triangles.size())
        throw Error("build_spatial_split_bvh: " + std::to_string(leaf_groups.size()) +
                    " leaf groups for " + std::to_string(mesh.triangles.size()) + " triangles");
    const std::vector<BuildPrim> prims = make_triangle_build_prims(mesh);
    const std::uint64_t capacity =
        prims.size() + std::uint64_t(double(prims.size()) * settings.spatial_split_budget);
    if (capacity > std::uint64_t(NodeRef::kMaxFirst))
        throw Error("build_spatial_split_bvh: " + std::to_string(capacity) +
                    " references exceed the limit of " + std::to_string(NodeRef::kMaxFirst));
    SpatialSplitBvh out;
    if (prims.empty()) return out;
    const ScratchBuffer<BuildPrim> refs_buffer(capacity), scratch_buffer(capacity);
    const std::span<BuildPrim> refs = refs_buffer.span();
    std::copy(prims.begin(), prims.end(), refs.begin());
    ThreadSearchCounts counts;
    SpatialSplitBvhBuilder builder(mesh, refs, scratch_buffer.span(), settings, leaf_groups,
                                   counts);
    const RangeInfo info =
        compute_range_info(refs.first(prims.size()), settings.parallel_threshold);
    builder.set_root_area(info.bounds.half_area());
    const SegmentCandidate root = builder.evaluate(0, std::uint32_t(prims.size()),
                                                   std::uint32_t(capacity), false, info, false, 0);
    out.tree.bounds = info.bounds;
    if (root.is_leaf) {
        out.tree.root = NodeRef::leaf(0, root.size());
    } else {
        const OptimalWideTreeGrower<SpatialSplitBvhBuilder, SegmentCandidate> grower(
            builder, settings.task_threshold, settings.max_children);
        out.tree.root = grower.grow(root, out.tree.nodes);
    }
    out.leaf_prims = compact_leaves(out.tree, refs);
    for (const SpatialSplitSearchCounts& thread : counts) {
        out.search_counts.candidates += thread.candidates;
        out.search_counts.searches += thread.searches;
        out.search_counts.cheaper += thread.cheaper;
        out.search_counts.longest_fruitless_run =
            std::max(out.search_counts.longest_fruitless_run, thread.longest_fruitless_run);
    }
    return out;
}

}  // namespace rebraid
