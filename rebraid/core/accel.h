#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "rebraid/core/ray.h"

namespace rebraid {

/// Work one ray caused; the viewer's heatmap and the benchmarks read these.
struct TraversalCounters {
    std::uint64_t nodes_visited = 0;     ///< wide nodes whose children were box-tested
    std::uint64_t triangles_tested = 0;  ///< ray-triangle tests
    /// Top-level items entered: each maps the ray into an instance's object space and starts
    /// a traversal of its object BVH (two-level structures only; 0 for flat ones).
    std::uint64_t object_entries = 0;
};

/// What `rebraid stats` reports for a structure. Fields that do not apply to a structure
/// (e.g. `top_build_ms` for a flat BVH, `brefs` for anything but rebraid) stay empty.
struct AccelStats {
    std::uint64_t triangles = 0;  ///< triangles over all instances
    std::uint64_t instances = 0;
    std::uint64_t meshes = 0;
    double build_ms = 0.0;  ///< whole build: object BVHs + top level
    std::optional<double> top_build_ms;
    std::optional<double> sah;  ///< see docs/design.md, "SAH": 1 per node visited, 1 per triangle
    std::optional<std::uint64_t> nodes;
    std::optional<std::uint64_t> leaves;
    std::optional<std::uint64_t> memory_bytes;
    std::optional<std::uint64_t> structure_hash;
    std::optional<std::uint64_t> brefs;   ///< rebraid: BRefs after opening
    std::optional<std::uint64_t> budget;  ///< rebraid: BRef array capacity
    std::optional<std::uint64_t> opened;  ///< rebraid: BRefs opened
    /// rebraid: world-space copies of meshes that several instances place, beyond the meshes
    /// (`meshes` counts the scene's; RebraidSettings::world_space_copy_budget).
    std::optional<std::uint64_t> mesh_copies;
    /// Instruction set of the traversal kernels rays take (simd_level.h), where one is chosen.
    std::optional<std::string> kernels;
    /// Ray-triangle test of the traversal (triangle_test.h), where one is chosen.
    std::optional<std::string> triangle_test;
};

/// A built acceleration structure over a Scene, answering rays in the project's terms
/// (instance index in glTF depth-first order, primID within the mesh). Implementations are
/// immutable after construction and safe to query from many threads at once.
class Accel {
public:
    virtual ~Accel() = default;

    /// Closest hit with tnear <= t <= tfar, or a miss.
    Hit intersect(const Ray& ray) const { return intersect_counted(ray, nullptr); }
    /// Same, adding the work done to `counters` when it is not null.
    virtual Hit intersect_counted(const Ray& ray, TraversalCounters* counters) const = 0;
    /// True when any hit with tnear <= t <= tfar exists.
    virtual bool occluded(const Ray& ray) const = 0;
    virtual AccelStats stats() const = 0;
};

}  // namespace rebraid
