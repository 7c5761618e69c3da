#include "embree_glue/reference/embree_bvh_builder.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "embree_glue/reference/embree_geometry.h"
#include "rebraid/core/error.h"

namespace rebraid::glue {
namespace {

// ---- The pointer tree Embree grows through the callbacks ---------------------------------
// Both node kinds live in memory from rtcThreadLocalAlloc, which Embree frees with the
// RTCBVH; they are plain data, so nothing needs destroying. Both start with their kind, so
// a child pointer can be inspected before its type is known.

enum class PointerNodeKind : std::uint32_t { inner, leaf };

struct PointerInner {
    PointerNodeKind kind = PointerNodeKind::inner;
    std::uint32_t child_count = 0;
    const void* children[kBvhWidth] = {};
    BBox3f child_bounds[kBvhWidth];
};

struct PointerLeaf {
    PointerNodeKind kind = PointerNodeKind::leaf;
    std::uint32_t prim_count = 0;
    PrimId prim_ids[kMaxLeafSize] = {};
};

static_assert(std::is_standard_layout_v<PointerInner> && std::is_standard_layout_v<PointerLeaf>,
              "the kind must be readable through a pointer to the first member");

PointerNodeKind kind_of(const void* node) {
    return *static_cast<const PointerNodeKind*>(node);
}

/// What can go wrong inside a callback. Callbacks must not throw (an exception cannot cross
/// Embree's C frames), so they record the first problem here and the build throws after
/// rtcBuildBVH has returned.
enum class CallbackFailure : int { none, allocation, too_many_children, leaf_too_large };

/// The user pointer every callback receives.
struct BuildContext {
    /// Corners of every triangle by primID, for spatial splits (empty without them): one
    /// contiguous load per split instead of an index and three vertex lookups.
    std::vector<TriangleVerts> triangles;
    std::atomic<int> first_failure{int(CallbackFailure::none)};
    /// Inner nodes created, to size the node array once (a sum: the same in any order).
    std::atomic<std::size_t> inner_count{0};

    void fail(CallbackFailure failure) noexcept {
        int expected = int(CallbackFailure::none);
        first_failure.compare_exchange_strong(expected, int(failure));
    }
};

BuildContext& context_of(void* user) {
    return *static_cast<BuildContext*>(user);
}

void* create_inner(RTCThreadLocalAllocator allocator, unsigned int child_count,
                   void* user) noexcept {
    void* memory = rtcThreadLocalAlloc(allocator, sizeof(PointerInner), alignof(PointerInner));
    if (memory == nullptr) {
        context_of(user).fail(CallbackFailure::allocation);
        return nullptr;
    }
    if (child_count > unsigned(kBvhWidth))
        context_of(user).fail(CallbackFailure::too_many_children);
    context_of(user).inner_count.fetch_add(1, std::memory_order_relaxed);
    PointerInner* node = std::construct_at(static_cast<PointerInner*>(memory));
    node->child_count = std::min(child_count, unsigned(kBvhWidth));
    return node;
}

void set_inner_children(void* node, void** children, unsigned int child_count,
                        void* /*user*/) noexcept {
    if (node == nullptr) return;  // its allocation failed: already recorded
    auto* inner = static_cast<PointerInner*>(node);
    const unsigned int count = std::min(child_count, inner->child_count);
    for (unsigned int i = 0; i < count; ++i) inner->children[i] = children[i];
}

void set_inner_bounds(void* node, const RTCBounds** bounds, unsigned int child_count,
                      void* /*user*/) noexcept {
    if (node == nullptr) return;
    auto* inner = static_cast<PointerInner*>(node);
    const unsigned int count = std::min(child_count, inner->child_count);
    for (unsigned int i = 0; i < count; ++i) {
        const RTCBounds& b = *bounds[i];
        inner->child_bounds[i] = {{b.lower_x, b.lower_y, b.lower_z},
                                  {b.upper_x, b.upper_y, b.upper_z}};
    }
}

void* create_leaf(RTCThreadLocalAllocator allocator, const RTCBuildPrimitive* prims,
                  size_t prim_count, void* user) noexcept {
    void* memory = rtcThreadLocalAlloc(allocator, sizeof(PointerLeaf), alignof(PointerLeaf));
    if (memory == nullptr) {
        context_of(user).fail(CallbackFailure::allocation);
        return nullptr;
    }
    if (prim_count > kMaxLeafSize) context_of(user).fail(CallbackFailure::leaf_too_large);
    PointerLeaf* leaf = std::construct_at(static_cast<PointerLeaf*>(memory));
    leaf->prim_count = std::uint32_t(std::min<size_t>(prim_count, kMaxLeafSize));
    for (std::uint32_t i = 0; i < leaf->prim_count; ++i) leaf->prim_ids[i] = prims[i].primID;
    // Embree's partitioning may leave a leaf's primitives in an order that depends on thread
    // timing; sorted ids make the leaf (and the whole tree) independent of it.
    std::sort(leaf->prim_ids, leaf->prim_ids + leaf->prim_count);
    return leaf;
}

/// Spatial splits: the bounds of the parts of a (possibly already clipped) triangle on
/// either side of the plane x[dimension] = position.
void split_triangle(const RTCBuildPrimitive* prim, unsigned int dimension, float position,
                    RTCBounds* left_bounds, RTCBounds* right_bounds, void* user) noexcept {
    // Embree calls this for every bin plane a primitive spans, at every level of the build:
    // it dominates the build time with splits, so it is kept lean.
    const TriangleVerts& tri = context_of(user).triangles[prim->primID];
    const Vec3f corners[3] = {tri.v0, tri.v1, tri.v2};
    const int axis = int(dimension);
    float offsets[3];
    for (int i = 0; i < 3; ++i) offsets[i] = corners[i][axis] - position;
    BBox3f left, right;
    for (int i = 0; i < 3; ++i) {
        const int next = i == 2 ? 0 : i + 1;
        const float da = offsets[i], db = offsets[next];
        if (da <= 0.0f) left.extend(corners[i]);
        if (da >= 0.0f) right.extend(corners[i]);
        // An edge crossing the plane adds its crossing point to both sides.
        if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
            Vec3f crossing = corners[i] + (corners[next] - corners[i]) * (da / (da - db));
            crossing[axis] = position;
            left.extend(crossing);
            right.extend(crossing);
        }
    }
    // The primitive may be a part clipped earlier: its parts stay inside its current box.
    const BBox3f current{{prim->lower_x, prim->lower_y, prim->lower_z},
                         {prim->upper_x, prim->upper_y, prim->upper_z}};
    left = intersection(left, current);
    right = intersection(right, current);
    *left_bounds = {left.min.x, left.min.y, left.min.z, 0.0f,
                    left.max.x, left.max.y, left.max.z, 0.0f};
    *right_bounds = {right.min.x, right.min.y, right.min.z, 0.0f,
                     right.max.x, right.max.y, right.max.z, 0.0f};
}

// ---- Conversion into the project's layout ------------------------------------------------

/// Walks the pointer tree depth first, numbering inner nodes in pre-order and appending each
/// leaf's primIDs to the leaf order, so the result depends only on the tree's shape.
class TreeConverter {
public:
    TreeConverter(std::size_t inner_count, std::size_t expected_prim_count) {
        nodes_.reserve(inner_count);
        leaf_prims_.reserve(expected_prim_count);
    }

    NodeRef convert(const void* pointer, int depth) {
        if (pointer == nullptr) throw Error("rtcBuildBVH: Embree returned a tree with a null node");
        if (depth > kMaxBvhDepth)
            throw Error("rtcBuildBVH: tree deeper than kMaxBvhDepth (" +
                        std::to_string(kMaxBvhDepth) + ")");
        if (kind_of(pointer) == PointerNodeKind::leaf) {
            const auto& leaf = *static_cast<const PointerLeaf*>(pointer);
            const std::size_t first = leaf_prims_.size();
            if (leaf.prim_count == 0) throw Error("rtcBuildBVH: Embree created an empty leaf");
            if (first > NodeRef::kMaxFirst)
                throw Error("rtcBuildBVH: " + std::to_string(first) +
                            " primitive references exceed NodeRef's range");
            leaf_prims_.insert(leaf_prims_.end(), leaf.prim_ids, leaf.prim_ids + leaf.prim_count);
            return NodeRef::leaf(std::uint32_t(first), leaf.prim_count);
        }
        const auto& inner = *static_cast<const PointerInner*>(pointer);
        const auto node_id = std::uint32_t(nodes_.size());
        nodes_.push_back(WideNode::make_empty());
        for (std::uint32_t i = 0; i < inner.child_count; ++i) {
            const NodeRef child = convert(inner.children[i], depth + 1);
            // nodes_ may have grown: index again rather than keeping a reference.
            nodes_[node_id].set_child(int(i), child, inner.child_bounds[i]);
        }
        return NodeRef::inner(node_id);
    }

    std::vector<WideNode>& nodes() { return nodes_; }
    std::vector<PrimId>& leaf_prims() { return leaf_prims_; }

private:
    std::vector<WideNode> nodes_;
    std::vector<PrimId> leaf_prims_;
};

// ---- Helpers -------------------------------------------------------------------------------

struct BvhReleaser {
    void operator()(RTCBVH bvh) const { rtcReleaseBVH(bvh); }
};
/// Owns an RTCBVH; releasing it frees every node the callbacks allocated.
using BvhHandle = std::unique_ptr<std::remove_pointer_t<RTCBVH>, BvhReleaser>;

/// One build primitive per triangle (object-space bounds, primID = triangle index) in the
/// first `mesh.triangles.size()` entries of `prims`; returns their union.
BBox3f fill_build_prims(const Mesh& mesh, std::vector<RTCBuildPrimitive>& prims) {
    const std::size_t count = mesh.triangles.size();
    // Min and max are exact, so the reduction gives the same box in any combination order.
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, 1024), BBox3f{},
        [&](const tbb::blocked_range<std::size_t>& range, BBox3f bounds) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                BBox3f box;
                for (Vec3f corner : mesh.corners(PrimId(i))) box.extend(corner);
                prims[i] = {box.min.x, box.min.y, box.min.z, 0u,
                            box.max.x, box.max.y, box.max.z, std::uint32_t(i)};
                bounds.extend(box);
            }
            return bounds;
        },
        [](BBox3f a, const BBox3f& b) { return merge(a, b); });
}

const char* failure_text(CallbackFailure failure) {
    switch (failure) {
        case CallbackFailure::none:
            return "no failure";
        case CallbackFailure::allocation:
            return "rtcThreadLocalAlloc returned no memory";
        case CallbackFailure::too_many_children:
            return "Embree asked for a node wider than kBvhWidth";
        case CallbackFailure::leaf_too_large:
            return "Embree created a leaf larger than kMaxLeafSize";
    }
    return "unknown failure";
}

}  // namespace

void EmbreeBvhBuilderSettings::validate() const {
    const auto fail = [](const std::string& what) {
        throw Error("EmbreeBvhBuilderSettings: " + what);
    };
    if (quality != EmbreeBuildQuality::low && quality != EmbreeBuildQuality::medium &&
        quality != EmbreeBuildQuality::high)
        fail("quality " + std::to_string(int(quality)) + " is not low, medium or high");
    if (max_branching_factor < 2 || max_branching_factor > std::uint32_t(kBvhWidth))
        fail("max_branching_factor " + std::to_string(max_branching_factor) + " is outside 2.." +
             std::to_string(kBvhWidth));
    if (max_depth < 1 || max_depth > std::uint32_t(kMaxBvhDepth))
        fail("max_depth " + std::to_string(max_depth) + " is outside 1.." +
             std::to_string(kMaxBvhDepth));
    if (max_leaf_size < 1 || max_leaf_size > kMaxLeafSize)
        fail("max_leaf_size " + std::to_string(max_leaf_size) + " is outside 1.." +
             std::to_string(kMaxLeafSize));
    if (min_leaf_size < 1 || min_leaf_size > max_leaf_size)
        fail("min_leaf_size " + std::to_string(min_leaf_size) + " is outside 1..max_leaf_size (" +
             std::to_string(max_leaf_size) + ")");
    if (sah_block_size < 1 || sah_block_size > kMaxLeafSize ||
        (sah_block_size & (sah_block_size - 1)) != 0)
        fail("sah_block_size " + std::to_string(sah_block_size) + " is not a power of two in 1.." +
             std::to_string(kMaxLeafSize));
    if (!(traversal_cost >= 0.0f) || !std::isfinite(traversal_cost))
        fail("traversal_cost " + std::to_string(traversal_cost) + " must be finite and >= 0");
    if (!(intersection_cost > 0.0f) || !std::isfinite(intersection_cost))
        fail("intersection_cost " + std::to_string(intersection_cost) + " must be finite and > 0");
}

ObjectBvh build_object_bvh_embree(EmbreeDevice& device, const Mesh& mesh,
                                  const EmbreeBvhBuilderSettings& settings) {
    settings.validate();
    const auto start = std::chrono::steady_clock::now();
    const std::size_t triangle_count = mesh.triangles.size();
    const auto finish = [&](ObjectBvh bvh) {
        bvh.build_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        return bvh;
    };
    if (triangle_count == 0) return finish(ObjectBvh{});  // Embree has nothing to build
    if (triangle_count > NodeRef::kMaxFirst)
        throw Error("build_object_bvh_embree: mesh '" + mesh.name + "' has " +
                    std::to_string(triangle_count) + " triangles, more than NodeRef indexes (" +
                    std::to_string(NodeRef::kMaxFirst) + ")");

    const bool has_splits =
        settings.quality == EmbreeBuildQuality::high && settings.can_split_triangles;
    // Spatial splits store the clipped parts after the originals: Embree's documentation
    // suggests room for about twice the primitives.
    std::vector<RTCBuildPrimitive> prims(has_splits ? 2 * triangle_count : triangle_count);
    const BBox3f bounds = fill_build_prims(mesh, prims);

    BvhHandle bvh(rtcNewBVH(device.get()));
    device.throw_if_error("rtcNewBVH");
    if (!bvh) throw Error("rtcNewBVH: Embree returned no BVH");

    BuildContext context;
    if (has_splits) {
        context.triangles.resize(triangle_count);
        tbb::parallel_for(std::size_t(0), triangle_count, [&](std::size_t i) {
            const auto corners = mesh.corners(PrimId(i));
            context.triangles[i] = {corners[0], corners[1], corners[2]};
        });
    }
    RTCBuildArguments arguments = rtcDefaultBuildArguments();
    arguments.buildQuality = to_embree_quality(settings.quality);
    arguments.maxBranchingFactor = settings.max_branching_factor;
    arguments.maxDepth = settings.max_depth;
    arguments.sahBlockSize = settings.sah_block_size;
    arguments.minLeafSize = settings.min_leaf_size;
    arguments.maxLeafSize = settings.max_leaf_size;
    arguments.traversalCost = settings.traversal_cost;
    arguments.intersectionCost = settings.intersection_cost;
    arguments.bvh = bvh.get();
    arguments.primitives = prims.data();
    arguments.primitiveCount = triangle_count;
    arguments.primitiveArrayCapacity = prims.size();
    arguments.createNode = &create_inner;
    arguments.setNodeChildren = &set_inner_children;
    arguments.setNodeBounds = &set_inner_bounds;
    arguments.createLeaf = &create_leaf;
    arguments.splitPrimitive = has_splits ? &split_triangle : nullptr;
    arguments.userPtr = &context;

    const void* root = rtcBuildBVH(&arguments);
    const std::string call =
        "rtcBuildBVH (mesh '" + mesh.name + "', " + std::to_string(triangle_count) + " triangles)";
    device.throw_if_error(call.c_str());
    if (const auto failure = CallbackFailure(context.first_failure.load());
        failure != CallbackFailure::none)
        throw Error(call + ": " + failure_text(failure));
    if (root == nullptr) throw Error(call + ": Embree returned no tree");

    TreeConverter converter(context.inner_count.load(),
                            has_splits ? triangle_count + triangle_count / 4 : triangle_count);
    WideBvh tree;
    tree.root = converter.convert(root, 0);
    tree.nodes = std::move(converter.nodes());
    tree.bounds = bounds;
    bvh.reset();  // the pointer tree is no longer needed
    return finish(make_object_bvh(mesh, std::move(tree), std::move(converter.leaf_prims())));
}

ObjectBvh build_object_bvh_embree(const Mesh& mesh, const EmbreeBvhBuilderSettings& settings) {
    settings.validate();
    EmbreeDevice device;
    return build_object_bvh_embree(device, mesh, settings);
}

ObjectBvhBuilder embree_object_bvh_builder(const EmbreeBvhBuilderSettings& settings) {
    settings.validate();
    auto device = std::make_shared<EmbreeDevice>();
    return [device, settings](const Mesh& mesh) {
        return build_object_bvh_embree(*device, mesh, settings);
    };
}

}  // namespace rebraid::glue
