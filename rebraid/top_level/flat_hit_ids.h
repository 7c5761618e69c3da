#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

#include "rebraid/core/types.h"

namespace rebraid {

/// How a flat BVH's leaves name the instance and the primID of a hit in one 32-bit word: the
/// primID in the low `prim_bits` bits, the instance above them. Where every pair fits
/// (`packs`), FlatAccel keeps the word in the id row of its leaf rows (leaf_rows.h), so the
/// hit is named by the leaf the test has just read, as the rows of object BVHs name their
/// primIDs; elsewhere, and for kernels that read no rows, by FlatAccel's tables per world
/// triangle, whose lookup after the traversal was a cache miss per hit on scenes larger than
/// the caches.
struct FlatHitIds {
    bool packs = false;
    std::uint32_t prim_bits = 0;

    /// The packing for `instances` instances whose meshes hold at most `max_mesh_triangles`
    /// triangles: it packs when the largest instance index and primID fit 32 bits together.
    static FlatHitIds for_scene(std::size_t instances, std::size_t max_mesh_triangles) {
        const auto bits = [](std::size_t count) {
            return count == 0 ? 0 : int(std::bit_width(std::uint64_t(count - 1)));
        };
        FlatHitIds ids;
        ids.prim_bits = std::uint32_t(bits(max_mesh_triangles));
        ids.packs = ids.prim_bits < 32 && bits(instances) + int(ids.prim_bits) <= 32;
        return ids;
    }

    /// Precondition: packs, and the pair within the counts for_scene was given.
    std::uint32_t pack(InstanceId instance, PrimId prim) const {
        return (std::uint32_t(instance) << prim_bits) | prim;
    }
    InstanceId instance_of(std::uint32_t word) const { return InstanceId(word >> prim_bits); }
    PrimId prim_of(std::uint32_t word) const {
        return PrimId(word & ((std::uint32_t(1) << prim_bits) - 1u));
    }
};

}  // namespace rebraid
