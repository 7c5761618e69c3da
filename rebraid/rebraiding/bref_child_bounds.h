#pragma once

#include <tbb/concurrent_vector.h>

#include <array>
#include <cstdint>
#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/zeroed_buffer.h"
#include "rebraid/rebraiding/bref.h"

namespace rebraid {

/// The world boxes of the children of BRefs to inner object nodes, kept per target slot for
/// one build. The SAH-aware rules ask for them each time a BRef is a candidate (at every
/// level until it opens or its segment stops opening) and once more when it opens; each
/// costs a search of the object BVH (vertex bounds), so they are computed once per BRef.
/// A slot belongs to one segment at a time, so no two tasks touch the same slot's entry; the
/// entries' order depends on the tasks' timing, their contents do not.
class BRefChildBounds {
public:
    using Boxes = std::array<BBox3f, kBvhWidth>;

    /// For target slots [0, slots).
    explicit BRefChildBounds(std::size_t slots) : entry_of_slot_(slots) {}

    /// The boxes stored for `slot`'s BRef when they were computed for `target`, else null.
    const Boxes* find(std::uint32_t slot, const BRefTarget& target) const {
        const std::uint32_t entry_plus_one = entry_of_slot_[slot];
        if (entry_plus_one == 0) return nullptr;
        const Entry& e = entries_[entry_plus_one - 1];
        const bool is_same = e.target.instance_id == target.instance_id &&
                             e.target.object_node == target.object_node;
        return is_same ? &e.boxes : nullptr;
    }

    /// Stores `boxes` as those of `slot`'s BRef, now to `target`.
    const Boxes& store(std::uint32_t slot, const BRefTarget& target, const Boxes& boxes) {
        const auto it = entries_.push_back({target, boxes});
        entry_of_slot_[slot] = std::uint32_t(it - entries_.begin()) + 1;
        return it->boxes;
    }

private:
    struct Entry {
        BRefTarget target;
        Boxes boxes;
    };
    /// Per slot: 1 + the index of its entry, 0 for none (sized for every slot of the budget,
    /// of which a build may touch few).
    ZeroedBuffer<std::uint32_t> entry_of_slot_;
    tbb::concurrent_vector<Entry> entries_;
};

}  // namespace rebraid
