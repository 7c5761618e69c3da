#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace rebraid {

/// What partition_summarized returns: items [0, left_count) satisfied the predicate; `left`
/// and `right` summarise each side.
template <class Summary>
struct PartitionResult {
    std::size_t left_count = 0;
    Summary left, right;
};

/// Elements per block of the parallel partition. Blocks are fixed by position, never by the
/// thread count; the parallel partition is stable, so its result does not even depend on
/// this value.
inline constexpr std::size_t kPartitionBlock = 4096;

/// Moves the elements for which `goes_left` holds to the front of `items` and summarises
/// each side on the way: `Summary` is default-constructible (empty) with `add(const T&)` and
/// `merge(const Summary&)`, and merging must be exact (min/max, integer sums), so that any
/// division into blocks gives the same summary.
///
/// At or above `parallel_threshold` elements: a stable partition in two parallel passes over
/// fixed blocks. Pass 1 partitions each block into the same positions of `scratch` (left
/// elements forward from the block's start, right ones backward from its end) and counts
/// them; pass 2 copies both parts to slots from exclusive prefix sums over the blocks. The
/// predicate runs once per element. Below the threshold: an in-place serial partition
/// (Hoare's two scans; not stable). `scratch` needs items.size() elements on the parallel
/// path only. The result depends only on the input and the threshold.
template <class Summary, class T, class Predicate>
PartitionResult<Summary> partition_summarized(std::span<T> items, Predicate goes_left,
                                              std::size_t parallel_threshold,
                                              std::span<T> scratch) {
    PartitionResult<Summary> result;
    if (items.size() < parallel_threshold) {
        std::size_t first = 0, last = items.size();
        for (;;) {
            while (first < last && goes_left(items[first])) result.left.add(items[first++]);
            while (first < last && !goes_left(items[last - 1])) result.right.add(items[--last]);
            if (first == last) break;
            // items[first] goes right and items[last - 1] goes left: swap them into place.
            std::swap(items[first], items[last - 1]);
            result.left.add(items[first++]);
            result.right.add(items[--last]);
        }
        result.left_count = first;
        return result;
    }

    struct Block {
        std::size_t left_count = 0, left_offset = 0;
        Summary left, right;
    };
    const std::size_t n = items.size();
    const std::size_t block_count = (n + kPartitionBlock - 1) / kPartitionBlock;
    std::vector<Block> blocks(block_count);
    tbb::parallel_for(std::size_t(0), block_count, [&](std::size_t b) {
        const std::size_t begin = b * kPartitionBlock, end = std::min(n, begin + kPartitionBlock);
        Block& block = blocks[b];
        std::size_t left = begin, right = end;
        for (std::size_t i = begin; i < end; ++i) {
            if (goes_left(items[i])) {
                block.left.add(items[i]);
                scratch[left++] = items[i];
            } else {
                block.right.add(items[i]);
                scratch[--right] = items[i];
            }
        }
        block.left_count = left - begin;
    });
    // Exclusive prefix sums: block b's left part starts at left_offset, its right part at
    // left_total + (begin - left_offset) (the right elements of the blocks before it).
    std::size_t left_total = 0;
    for (Block& block : blocks) {
        block.left_offset = left_total;
        left_total += block.left_count;
        result.left.merge(block.left);
        result.right.merge(block.right);
    }
    tbb::parallel_for(std::size_t(0), block_count, [&](std::size_t b) {
        const std::size_t begin = b * kPartitionBlock, end = std::min(n, begin + kPartitionBlock);
        const Block& block = blocks[b];
        const std::size_t split = begin + block.left_count;
        std::copy(scratch.begin() + begin, scratch.begin() + split,
                  items.begin() + block.left_offset);
        // The right part was written backwards: reverse it back into input order.
        std::reverse_copy(scratch.begin() + split, scratch.begin() + end,
                          items.begin() + left_total + (begin - block.left_offset));
    });
    result.left_count = left_total;
    return result;
}

/// A Summary that records nothing, for plain partitions.
struct NoSummary {
    template <class T>
    void add(const T&) {}
    void merge(const NoSummary&) {}
};

/// Moves the elements for which `goes_left` holds to the front and returns how many there
/// are (partition_summarized without summaries, with its own scratch space). The result
/// depends only on the input and `parallel_threshold`, never on the thread count or timing.
template <class T, class Predicate>
std::size_t parallel_partition(std::span<T> items, Predicate goes_left,
                               std::size_t parallel_threshold) {
    std::unique_ptr<T[]> scratch;
    if (items.size() >= parallel_threshold) scratch = std::make_unique<T[]>(items.size());
    return partition_summarized<NoSummary>(
               items, goes_left, parallel_threshold,
               std::span<T>(scratch.get(), scratch ? items.size() : 0))
        .left_count;
}

}  // namespace rebraid
