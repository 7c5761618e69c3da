#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <memory>
#include <span>
#include <type_traits>
#include <vector>

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "rebraid/core/parallel_blocks.h"

namespace rebraid {

/// What the partitions below return: elements [0, left_count) of the output satisfied the
/// predicate; `left` and `right` summarise each side.
template <class Summary>
struct PartitionResult {
    std::size_t left_count = 0;
    Summary left, right;
};

namespace partition_detail {

/// Copies one element as raw bytes: a 32-byte BuildPrim then moves with one vector load and
/// store rather than field by field (partitioning is bound by stores).
template <class T>
void copy_element(T* to, const T* from) {
#if defined(__AVX__)
    // Compilers tuned for generic x86-64 expand a 32-byte memcpy into two 16-byte moves.
    if constexpr (sizeof(T) == 32) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(to),
                            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(from)));
        return;
    }
#endif
    std::memcpy(static_cast<void*>(to), static_cast<const void*>(from), sizeof(T));
}

/// Adds items[begin, end) to `summary`, accumulating in a local: the summary's fields could
/// alias the items' as far as the compiler knows, and would go through memory every step.
template <class Summary, class T>
void summarize(Summary& summary, const T* items, std::size_t begin, std::size_t end) {
    Summary local;
    for (std::size_t i = begin; i < end; ++i) local.add(items[i]);
    summary.merge(local);
}

/// Branch-free partition of in[0, count) into out[0, count): left elements forward from the
/// front, right ones backward from the back (so the right side comes out reversed). The
/// destination is selected, not branched to.
template <class T, class Predicate>
std::size_t partition_two_sided(const T* in, std::size_t count, T* out, Predicate goes_left) {
    T* left = out;
    T* right = out + count;
    for (std::size_t i = 0; i < count; ++i) {
        const bool is_left = goes_left(in[i]);
        copy_element(is_left ? left : right - 1, in + i);
        left += is_left;
        right -= !is_left;
    }
    return std::size_t(left - out);
}

/// Branch-free stable scatter of in[0, count) to the runs starting at `left` and `right`.
template <class T, class Predicate>
void scatter(const T* in, std::size_t count, T* left, T* right, Predicate goes_left) {
    for (std::size_t i = 0; i < count; ++i) {
        const bool is_left = goes_left(in[i]);
        copy_element(is_left ? left : right, in + i);
        left += is_left;
        right += !is_left;
    }
}

}  // namespace partition_detail

/// Partitions `in` into `out` (same size, distinct memory): the elements for which
/// `goes_left` holds first, and summarises each side while it is in cache: `Summary` is
/// default-constructible (empty) with `add(const T&)` and `merge(const Summary&)`, and
/// merging must be exact (min/max, integer sums), so that any division into blocks gives
/// the same summary. T must be trivially copyable.
///
/// Below `parallel_threshold` elements: one serial pass writing left elements forward and
/// right ones backward. At or above it, two parallel passes over fixed blocks: count each
/// block's left elements, then scatter every block to slots from exclusive prefix sums (a
/// stable partition). The result depends only on the input and the threshold, never on the
/// thread count or timing.
template <class Summary, class T, class Predicate>
PartitionResult<Summary> partition_summarized_into(std::span<const T> in, std::span<T> out,
                                                   Predicate goes_left,
                                                   std::size_t parallel_threshold) {
    static_assert(std::is_trivially_copyable_v<T>);
    using namespace partition_detail;
    PartitionResult<Summary> result;
    const std::size_t n = in.size();
    if (n < parallel_threshold) {
        result.left_count = partition_two_sided(in.data(), n, out.data(), goes_left);
        summarize(result.left, out.data(), 0, result.left_count);
        summarize(result.right, out.data(), result.left_count, n);
        return result;
    }

    struct Block {
        std::size_t left_count = 0, left_offset = 0;
        Summary left, right;
    };
    std::vector<Block> blocks(parallel_block_count(n));
    for_each_block(n, [&](std::size_t b, std::size_t begin, std::size_t end) {
        std::size_t count = 0;
        for (std::size_t i = begin; i < end; ++i) count += goes_left(in[i]);
        blocks[b].left_count = count;
    });
    // Exclusive prefix sums: block b's left elements go to left_offset, its right ones to
    // left_total + (begin - left_offset) (after the right elements of the blocks before it).
    std::size_t left_total = 0;
    for (Block& block : blocks) {
        block.left_offset = left_total;
        left_total += block.left_count;
    }
    for_each_block(n, [&](std::size_t b, std::size_t begin, std::size_t end) {
        Block& block = blocks[b];
        const std::size_t right_offset = left_total + (begin - block.left_offset);
        scatter(in.data() + begin, end - begin, out.data() + block.left_offset,
                out.data() + right_offset, goes_left);
        summarize(block.left, out.data(), block.left_offset, block.left_offset + block.left_count);
        summarize(block.right, out.data(), right_offset,
                  right_offset + (end - begin - block.left_count));
    });
    for (const Block& block : blocks) {
        result.left.merge(block.left);
        result.right.merge(block.right);
    }
    result.left_count = left_total;
    return result;
}

/// In-place form of partition_summarized_into, with the same result order: partitions into
/// `scratch` (at least items.size() elements, contents ignored) and copies back; without
/// scratch it partitions from a temporary copy of the input instead. The result depends only on the
/// input and the threshold, never on the thread count.
template <class Summary, class T, class Predicate>
PartitionResult<Summary> partition_summarized(std::span<T> items, Predicate goes_left,
                                              std::size_t parallel_threshold,
                                              std::span<T> scratch) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t n = items.size();
    if (scratch.size() < n) {
        // Small ranges (the common case) copy to the stack, larger ones to the heap.
        constexpr std::size_t kStackBytes = 4096;
        alignas(T) unsigned char stack_copy[kStackBytes];
        std::unique_ptr<unsigned char[]> heap_copy;
        unsigned char* bytes = stack_copy;
        if (n * sizeof(T) > kStackBytes) {
            heap_copy = std::make_unique_for_overwrite<unsigned char[]>(n * sizeof(T));
            bytes = heap_copy.get();
        }
        std::memcpy(bytes, static_cast<const void*>(items.data()), n * sizeof(T));
        const std::span<const T> copy(reinterpret_cast<const T*>(bytes), n);
        return partition_summarized_into<Summary>(copy, items, goes_left, parallel_threshold);
    }
    const std::span<T> out = scratch.first(n);
    PartitionResult<Summary> result = partition_summarized_into<Summary>(
        std::span<const T>(items), out, goes_left, parallel_threshold);
    auto copy_back = [&](std::size_t begin, std::size_t end) {
        std::memcpy(static_cast<void*>(items.data() + begin),
                    static_cast<const void*>(out.data() + begin), (end - begin) * sizeof(T));
    };
    if (n < parallel_threshold) {
        copy_back(0, n);
    } else {
        for_each_block(
            n, [&](std::size_t, std::size_t begin, std::size_t end) { copy_back(begin, end); });
    }
    return result;
}

/// A Summary that records nothing, for plain partitions.
struct NoSummary {
    template <class T>
    void add(const T&) {}
    void merge(const NoSummary&) {}
};

/// Moves the elements for which `goes_left` holds to the front and returns how many there
/// are (partition_summarized without summaries or scratch), in the order of
/// partition_summarized_into. The result depends only on the input and
/// `parallel_threshold`, never on the thread count or timing.
template <class T, class Predicate>
std::size_t parallel_partition(std::span<T> items, Predicate goes_left,
                               std::size_t parallel_threshold) {
    return partition_summarized<NoSummary>(items, goes_left, parallel_threshold, std::span<T>())
        .left_count;
}

}  // namespace rebraid
