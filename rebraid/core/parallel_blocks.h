#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstddef>
#include <utility>

namespace rebraid {

/// The one way the library splits a pass over a large array for TBB: fixed blocks of
/// kParallelBlock elements, and a serial pass below a caller's threshold (splitting small
/// arrays costs more than it saves). Blocks are fixed by position, never by the thread count,
/// so passes whose output depends on the blocks are still the same on any thread count.
inline constexpr std::size_t kParallelBlock = 4096;

/// Elements [begin, end) of one block.
struct BlockRange {
    std::size_t begin = 0;
    std::size_t end = 0;
};

/// How many blocks a pass over `count` elements has.
inline std::size_t parallel_block_count(std::size_t count) {
    return (count + kParallelBlock - 1) / kParallelBlock;
}

/// Block `block` of a pass over `count` elements.
inline BlockRange parallel_block(std::size_t block, std::size_t count) {
    return {block * kParallelBlock, std::min(count, (block + 1) * kParallelBlock)};
}

/// Calls `body(block, begin, end)` for every block of [0, count), in parallel.
template <class Body>
void for_each_block(std::size_t count, const Body& body) {
    tbb::parallel_for(std::size_t(0), parallel_block_count(count), [&](std::size_t block) {
        const BlockRange range = parallel_block(block, count);
        body(block, range.begin, range.end);
    });
}

/// `body(begin, end, value) -> value` over [0, count), the partial values combined by
/// `join(a, b)`: one serial call below `serial_below` elements, else TBB over ranges of at
/// least kParallelBlock elements. TBB chooses how the ranges are cut and joined, so use it only
/// where that cannot change the result (min, max, integer sums, logical and/or).
template <class T, class Body, class Join>
T reduce_over_blocks(std::size_t count, std::size_t serial_below, T identity, const Body& body,
                     const Join& join) {
    if (count < serial_below) return body(std::size_t(0), count, std::move(identity));
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, kParallelBlock), std::move(identity),
        [&](const tbb::blocked_range<std::size_t>& range, T value) {
            return body(range.begin(), range.end(), std::move(value));
        },
        join);
}

}  // namespace rebraid
