#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

namespace rebraid {

/// Moves the elements for which `goes_left` holds to the front and returns how many there
/// are. At or above `parallel_threshold` elements the work is split into fixed-size blocks
/// whose output slots come from prefix sums (a stable partition), below it std::partition
/// runs: the result depends only on the input, never on the thread count or timing.
template <class T, class Predicate>
std::size_t parallel_partition(std::span<T> items, Predicate goes_left,
                               std::size_t parallel_threshold) {
    if (items.size() < parallel_threshold)
        return std::size_t(std::partition(items.begin(), items.end(), goes_left) - items.begin());

    constexpr std::size_t kBlock = 4096;
    const std::size_t block_count = (items.size() + kBlock - 1) / kBlock;
    std::vector<std::size_t> left_counts(block_count);
    std::vector<unsigned char> flags(items.size());
    tbb::parallel_for(std::size_t(0), block_count, [&](std::size_t block) {
        const std::size_t begin = block * kBlock, end = std::min(items.size(), begin + kBlock);
        std::size_t count = 0;
        for (std::size_t i = begin; i < end; ++i) count += (flags[i] = goes_left(items[i]));
        left_counts[block] = count;
    });
    // Exclusive prefix sums: block b's left elements start at left_offset[b], its right
    // elements at total_left + (begin - left_offset[b]).
    std::vector<std::size_t> left_offsets(block_count);
    std::size_t total_left = 0;
    for (std::size_t b = 0; b < block_count; ++b) {
        left_offsets[b] = total_left;
        total_left += left_counts[b];
    }
    std::vector<T> scratch(items.size());
    tbb::parallel_for(std::size_t(0), block_count, [&](std::size_t block) {
        const std::size_t begin = block * kBlock, end = std::min(items.size(), begin + kBlock);
        std::size_t left = left_offsets[block];
        std::size_t right = total_left + (begin - left_offsets[block]);
        for (std::size_t i = begin; i < end; ++i) scratch[flags[i] ? left++ : right++] = items[i];
    });
    tbb::parallel_for(std::size_t(0), block_count, [&](std::size_t block) {
        const std::size_t begin = block * kBlock, end = std::min(items.size(), begin + kBlock);
        std::copy(scratch.begin() + begin, scratch.begin() + end, items.begin() + begin);
    });
    return total_left;
}

}  // namespace rebraid
