#include "rebraid/wide_bvh_builder.h"

#include <tbb/task_group.h>

#include <array>
#include <string>

#include "rebraid/binned_split.h"
#include "rebraid/error.h"
#include "rebraid/parallel_partition.h"

namespace rebraid {
namespace {

/// A range of prims considered as one child of the node being built.
struct Candidate {
    std::uint32_t begin = 0, end = 0;
    RangeInfo info;
    BinnedSplit split;
    bool is_leaf = true;
    std::uint32_t size() const { return end - begin; }
};

class WideBvhBuilder {
public:
    WideBvhBuilder(std::span<BuildPrim> prims, const BuildSettings& settings)
        : prims_(prims), settings_(settings) {}

    /// `median_only`: skip the SAH search and split ranges by index (bounds the tree depth).
    Candidate evaluate(std::uint32_t begin, std::uint32_t end, const RangeInfo& info,
                       bool median_only) const {
        Candidate c{begin, end, info, {}, true};
        const std::uint32_t n = c.size();
        if (n <= 1) return c;
        if (!median_only) c.split = find_binned_split(range(c), info, settings_);
        if (!c.split.is_valid()) {
            // Every centroid coincides: only an index split can make progress.
            c.is_leaf = n <= settings_.max_leaf_size;
            return c;
        }
        const float area = info.bounds.half_area();
        const float leaf_cost = settings_.intersection_cost * area * float(info.weight);
        const float split_cost =
            settings_.traversal_cost * area + settings_.intersection_cost * c.split.cost;
        c.is_leaf = n <= settings_.max_leaf_size && leaf_cost <= split_cost;
        return c;
    }

    std::array<Candidate, 2> split(const Candidate& c, bool median_only) const {
        std::uint32_t mid;
        if (c.split.is_valid()) {
            const BinnedSplit& s = c.split;
            mid = c.begin + std::uint32_t(parallel_partition(
                                range(c), [&](const BuildPrim& p) { return s.goes_left(p); },
                                settings_.parallel_threshold));
        } else {
            mid = c.begin + c.size() / 2;
        }
        // The children's centroid bounds drive their binning: one pass over each side.
        const RangeInfo left = compute_range_info(range(c.begin, mid), settings_.parallel_threshold);
        const RangeInfo right = compute_range_info(range(mid, c.end), settings_.parallel_threshold);
        return {evaluate(c.begin, mid, left, median_only),
                evaluate(mid, c.end, right, median_only)};
    }

    /// Builds the subtree of a candidate that is not a leaf into `out` (node indices local to
    /// `out`) and returns its reference.
    NodeRef build(const Candidate& c, std::uint32_t depth, std::vector<WideNode>& out) const {
        // Past kSahDepthLimit, SAH splits of adversarial inputs (e.g. geometric series of
        // positions) could go on peeling one prim at a time; index splits halve the range,
        // which bounds the depth, and with it the traversal stack, by kMaxDepth.
        const bool median_only = depth + 1 >= std::uint32_t(kSahDepthLimit);
        // Grow the node: split the largest splittable child until the node is full.
        std::array<Candidate, kBvhWidth> kids;
        int kid_count = 0;
        for (const Candidate& half : split(c, median_only)) kids[kid_count++] = half;
        while (kid_count < kBvhWidth) {
            int pick = -1;
            float largest = -1.0f;
            for (int i = 0; i < kid_count; ++i)
                if (!kids[i].is_leaf && kids[i].info.bounds.half_area() > largest) {
                    largest = kids[i].info.bounds.half_area();
                    pick = i;
                }
            if (pick < 0) break;
            const std::array<Candidate, 2> halves = split(kids[pick], median_only);
            for (int i = kid_count; i > pick + 1; --i) kids[i] = kids[i - 1];
            kids[pick] = halves[0];
            kids[pick + 1] = halves[1];
            ++kid_count;
        }

        const std::uint32_t node_id = std::uint32_t(out.size());
        out.push_back(WideNode::make_empty());
        // Large subtrees get their own node arrays, built concurrently and appended in child
        // order afterwards, so node numbering never depends on which task finished first.
        std::array<std::vector<WideNode>, kBvhWidth> chunks;
        std::array<NodeRef, kBvhWidth> chunk_roots;
        tbb::task_group tasks;
        for (int i = 0; i < kid_count; ++i) {
            const Candidate& kid = kids[i];
            if (kid.is_leaf) {
                out[node_id].set_child(i, NodeRef::leaf(kid.begin, kid.size()), kid.info.bounds);
            } else if (kid.size() >= settings_.parallel_threshold) {
                tasks.run([this, &kid, depth, &chunk = chunks[i], &root = chunk_roots[i]] {
                    root = build(kid, depth + 1, chunk);
                });
            } else {
                const NodeRef child = build(kid, depth + 1, out);
                out[node_id].set_child(i, child, kid.info.bounds);
            }
        }
        tasks.wait();
        for (int i = 0; i < kid_count; ++i) {
            if (chunks[i].empty()) continue;
            const std::uint32_t offset = std::uint32_t(out.size());
            for (WideNode& node : chunks[i])
                for (NodeRef& ref : node.children)
                    if (ref.is_inner()) ref = NodeRef::inner(ref.node_id() + offset);
            out.insert(out.end(), chunks[i].begin(), chunks[i].end());
            out[node_id].set_child(i, NodeRef::inner(chunk_roots[i].node_id() + offset),
                                   kids[i].info.bounds);
        }
        return NodeRef::inner(node_id);
    }

private:
    std::span<BuildPrim> range(const Candidate& c) const { return range(c.begin, c.end); }
    std::span<BuildPrim> range(std::uint32_t begin, std::uint32_t end) const {
        return prims_.subspan(begin, end - begin);
    }

    std::span<BuildPrim> prims_;
    const BuildSettings& settings_;
};

}  // namespace

WideBvh build_wide_bvh(std::span<BuildPrim> prims, const BuildSettings& settings) {
    settings.validate();
    if (prims.size() > std::size_t(NodeRef::kMaxFirst))
        throw Error("build_wide_bvh: " + std::to_string(prims.size()) +
                    " primitives exceed the limit of " + std::to_string(NodeRef::kMaxFirst));
    WideBvh bvh;
    if (prims.empty()) return bvh;
    const WideBvhBuilder builder(prims, settings);
    const RangeInfo info = compute_range_info(prims, settings.parallel_threshold);
    const Candidate root = builder.evaluate(0, std::uint32_t(prims.size()), info, false);
    bvh.bounds = info.bounds;
    bvh.root = root.is_leaf ? NodeRef::leaf(0, root.size()) : builder.build(root, 0, bvh.nodes);
    return bvh;
}

}  // namespace rebraid
