#include "rebraid/bvh/wide_bvh_builder.h"

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/optimal_wide_tree_grower.h"
#include "rebraid/core/error.h"
#include "rebraid/core/huge_pages.h"
#include "rebraid/core/scratch_buffer.h"

namespace rebraid {
namespace {

/// A range of prims considered as one child of the node being built, with its best split
/// (invalid when only an index split can make progress).
struct Candidate {
    std::uint32_t begin = 0, end = 0;
    RangeInfo info;
    float half_area = 0.0f;  ///< info.bounds.half_area(), which node growth compares often
    BinnedSplit split;
    bool is_leaf = true;
    /// Which buffer holds the range's prims: binned splits partition from one buffer into
    /// the other (the caller's array or the scratch), which saves copying back every time.
    bool in_scratch = false;
    std::uint32_t size() const { return end - begin; }
    float area() const { return half_area; }
    BBox3f bounds() const { return info.bounds; }
};

/// The nodes one task built, node 0 being its subtree's root, with local node ids. Subtrees
/// it handed to other tasks hang off it as links; build_wide_bvh() numbers all chunks in one
/// depth-first pass at the end, so node numbering never depends on which task finished first,
/// and every node is copied once (not once per task level).
struct NodeChunk {
    struct Link {
        std::uint32_t node_id;  ///< local id of the parent node in this chunk
        int slot;               ///< child slot of that node the linked subtree fills
        std::unique_ptr<NodeChunk> chunk;
    };
    std::vector<WideNode> nodes;
    std::vector<Link> links;
    std::uint32_t offset = 0;  ///< id of node 0 in the final array, set by assign_offsets
};

/// Numbers chunks depth first (a chunk, then its links in order) and lists them.
void assign_offsets(NodeChunk& chunk, std::uint32_t& next, std::vector<NodeChunk*>& order) {
    chunk.offset = next;
    next += std::uint32_t(chunk.nodes.size());
    order.push_back(&chunk);
    for (NodeChunk::Link& link : chunk.links) assign_offsets(*link.chunk, next, order);
}

/// Concatenates the chunk tree into one node array with global ids.
std::vector<WideNode> flatten_chunks(NodeChunk& root) {
    if (root.links.empty()) return std::move(root.nodes);
    std::vector<NodeChunk*> order;
    std::uint32_t total = 0;
    assign_offsets(root, total, order);
    std::vector<WideNode> nodes;
    nodes.reserve(total);
    advise_huge_pages(nodes.data(), total * sizeof(WideNode));
    nodes.resize(total);
    tbb::parallel_for(std::size_t(0), order.size(), [&](std::size_t c) {
        const NodeChunk& chunk = *order[c];
        WideNode* out = nodes.data() + chunk.offset;
        for (std::size_t i = 0; i < chunk.nodes.size(); ++i) {
            out[i] = chunk.nodes[i];
            for (NodeRef& ref : out[i].children)
                if (ref.is_inner()) ref = NodeRef::inner(ref.node_id() + chunk.offset);
        }
        for (const NodeChunk::Link& link : chunk.links)
            out[link.node_id].children[link.slot] = NodeRef::inner(link.chunk->offset);
    });
    return nodes;
}

class WideBvhBuilder {
public:
    /// `scratch`: prims.size() elements, the second buffer partitions alternate with.
    WideBvhBuilder(std::span<BuildPrim> prims, std::span<BuildPrim> scratch,
                   const BuildSettings& settings)
        : prims_(prims), scratch_(scratch), settings_(settings) {}

    /// `median_only`: skip the SAH search and split ranges by index (bounds the tree depth).
    Candidate evaluate(std::uint32_t begin, std::uint32_t end, bool in_scratch,
                       const RangeInfo& info, bool median_only) const {
        Candidate c{begin, end, info, info.bounds.half_area(), {}, true, in_scratch};
        const std::uint32_t n = c.size();
        if (n <= 1) return c;
        if (!median_only) c.split = find_binned_split(range(c), info, settings_);
        if (!c.split.is_valid()) {
            // Every centroid coincides (or the depth limit holds): only an index split can
            // make progress.
            c.is_leaf = n <= settings_.max_leaf_size;
            return c;
        }
        const float leaf_cost = settings_.intersection_cost * c.half_area * float(info.weight);
        const float split_cost =
            settings_.traversal_cost * c.half_area + settings_.intersection_cost * c.split.cost;
        c.is_leaf = n <= settings_.max_leaf_size && leaf_cost <= split_cost;
        return c;
    }

    std::array<Candidate, 2> split(const Candidate& c, bool median_only) const {
        SplitResult s;
        bool in_scratch = c.in_scratch;
        if (c.split.is_valid()) {
            // The same order as apply_binned_split, which other builders use.
            bool moved = false;
            s = apply_split_in_or_across(range(c), range(c.begin, c.end, !c.in_scratch), c.split,
                                         settings_.parallel_threshold, moved);
            if (moved) in_scratch = !c.in_scratch;
        }
        // Binning and partition map centroids identically, so neither side is empty; should
        // one be, the index split below still makes progress.
        if (s.left_count > 0 && s.left_count < c.size()) {
            const std::uint32_t mid = c.begin + s.left_count;
            return {evaluate(c.begin, mid, in_scratch, s.left, median_only),
                    evaluate(mid, c.end, in_scratch, s.right, median_only)};
        }
        const std::uint32_t mid = c.begin + c.size() / 2;
        const std::size_t threshold = settings_.parallel_threshold;
        const RangeInfo left = compute_range_info(range(c.begin, mid, in_scratch), threshold);
        const RangeInfo right = compute_range_info(range(mid, c.end, in_scratch), threshold);
        return {evaluate(c.begin, mid, in_scratch, left, median_only),
                evaluate(mid, c.end, in_scratch, right, median_only)};
    }

    /// The leaf reference of a leaf candidate, its prims moved to the caller's array.
    NodeRef make_leaf(const Candidate& c) const {
        if (c.in_scratch) {
            const std::span<const BuildPrim> from = range(c);
            std::copy(from.begin(), from.end(), prims_.begin() + c.begin);
        }
        return NodeRef::leaf(c.begin, c.size());
    }

    /// An empty chunk for a subtree of `prim_count` prims, with room for the nodes it will
    /// likely hold (growing node arrays showed up in profiles as copying). A chunk holds its
    /// root and the subtrees of children below task_threshold; other children get chunks of
    /// their own. Small leaves make about one node per four prims.
    std::unique_ptr<NodeChunk> make_chunk(std::uint32_t prim_count) const {
        auto chunk = std::make_unique<NodeChunk>();
        const std::size_t inline_prims =
            std::min<std::size_t>(prim_count, kBvhWidth * settings_.task_threshold);
        chunk->nodes.reserve(1 + inline_prims / 4);
        return chunk;
    }

    /// Builds the subtree of a candidate that is not a leaf into `chunk` and returns its
    /// root's local reference.
    NodeRef build(const Candidate& c, std::uint32_t depth, NodeChunk& chunk) const {
        // Past kSahDepthLimit, SAH splits of adversarial inputs (e.g. geometric series of
        // positions) could go on peeling one prim at a time; index splits halve the range,
        // which bounds the depth, and with it the traversal stack, by kMaxDepth.
        const bool median_only = depth + 1 >= std::uint32_t(kSahDepthLimit);
        // Grow the node: split the largest splittable child until the node is full. Leaves
        // of more than one prim are split too: within a node a split costs no extra node
        // visit, so a full node of smaller leaves always lowers the SAH (the binary leaf test
        // in evaluate() charges a traversal a wide node does not pay).
        std::array<Candidate, kBvhWidth> kids;
        int kid_count = 0;
        for (const Candidate& half : split(c, median_only)) kids[kid_count++] = half;
        while (kid_count < int(settings_.max_children)) {
            int pick = -1;
            float largest = -1.0f;
            for (int i = 0; i < kid_count; ++i)
                if ((!kids[i].is_leaf || (settings_.fill_nodes && kids[i].size() > 1)) &&
                    kids[i].half_area > largest) {
                    largest = kids[i].half_area;
                    pick = i;
                }
            if (pick < 0) break;
            const std::array<Candidate, 2> halves = split(kids[pick], median_only);
            for (int i = kid_count; i > pick + 1; --i) kids[i] = kids[i - 1];
            kids[pick] = halves[0];
            kids[pick + 1] = halves[1];
            ++kid_count;
        }

        const std::uint32_t node_id = std::uint32_t(chunk.nodes.size());
        chunk.nodes.push_back(WideNode::make_empty());
        // Large children (by size alone, never by thread count) get chunks of their own and
        // are built as tasks; the last of them runs on this thread, saving a spawn.
        std::array<NodeChunk*, kBvhWidth> own_chunk{};
        int last_task = -1;
        for (int i = 0; i < kid_count; ++i) {
            if (kids[i].is_leaf || kids[i].size() < settings_.task_threshold) continue;
            chunk.links.push_back({node_id, i, make_chunk(kids[i].size())});
            own_chunk[i] = chunk.links.back().chunk.get();
            last_task = i;
        }
        // A task_group costs a context registration: most nodes spawn nothing and get none.
        std::optional<tbb::task_group> tasks;
        for (int i = 0; i < last_task; ++i) {
            if (!own_chunk[i]) continue;
            if (!tasks) tasks.emplace();
            tasks->run(
                [this, &kid = kids[i], depth, sub = own_chunk[i]] { build(kid, depth + 1, *sub); });
        }
        for (int i = 0; i < kid_count; ++i) {
            const Candidate& kid = kids[i];
            NodeRef child;  // linked chunks' references are filled in by flatten_chunks
            if (kid.is_leaf)
                child = make_leaf(kid);
            else if (!own_chunk[i])
                child = build(kid, depth + 1, chunk);
            chunk.nodes[node_id].set_child(i, child, kid.info.bounds);
        }
        if (last_task >= 0) build(kids[last_task], depth + 1, *own_chunk[last_task]);
        if (tasks) tasks->wait();
        return NodeRef::inner(node_id);
    }

private:
    std::span<BuildPrim> range(const Candidate& c) const {
        return range(c.begin, c.end, c.in_scratch);
    }
    std::span<BuildPrim> range(std::uint32_t begin, std::uint32_t end, bool in_scratch) const {
        return (in_scratch ? scratch_ : prims_).subspan(begin, end - begin);
    }

    std::span<BuildPrim> prims_;
    std::span<BuildPrim> scratch_;
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
    // One scratch buffer for the whole build (disjoint ranges use disjoint parts of it).
    const ScratchBuffer<BuildPrim> scratch(prims.size());
    const WideBvhBuilder builder(prims, scratch.span(), settings);
    const RangeInfo info = compute_range_info(prims, settings.parallel_threshold);
    const Candidate root = builder.evaluate(0, std::uint32_t(prims.size()), false, info, false);
    bvh.bounds = info.bounds;
    if (root.is_leaf) {
        bvh.root = NodeRef::leaf(0, root.size());
        return bvh;
    }
    if (settings.collapse == NodeCollapse::optimal) {
        const OptimalWideTreeGrower<WideBvhBuilder, Candidate> grower(
            builder, settings.task_threshold, settings.max_children);
        bvh.root = grower.grow(root, bvh.nodes);
        return bvh;
    }
    const std::unique_ptr<NodeChunk> chunk = builder.make_chunk(root.size());
    bvh.root = builder.build(root, 0, *chunk);
    bvh.nodes = flatten_chunks(*chunk);
    return bvh;
}

}  // namespace rebraid
