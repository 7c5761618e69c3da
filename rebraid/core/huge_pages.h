#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace rebraid {

/// Buffers smaller than this stay on ordinary pages: they fit the TLB anyway.
inline constexpr std::size_t kHugePageMinBytes = std::size_t(4) << 20;

/// Asks the OS to back the whole 4 KB pages of [data, data + bytes) with transparent huge
/// pages (Linux madvise MADV_HUGEPAGE; a no-op elsewhere or below kHugePageMinBytes). Why:
/// builds write tens of megabytes of fresh memory, and with 4 KB pages every first touch is a
/// page fault (profiles of 1.5M-triangle builds spent a fifth of their time in the kernel);
/// rays traced in random order touch nodes and triangles all over such arrays, and with 4 KB
/// pages nearly every access also misses the TLB. Only helps memory not touched yet. Best
/// effort: without THP support nothing changes.
inline void advise_huge_pages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (bytes < kHugePageMinBytes) return;
    constexpr std::uintptr_t kPage = 4096;
    const auto begin = reinterpret_cast<std::uintptr_t>(data);
    const std::uintptr_t first = (begin + kPage - 1) & ~(kPage - 1);
    const std::uintptr_t last = (begin + bytes) & ~(kPage - 1);
    if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
    (void)data;
    (void)bytes;
#endif
}

/// Makes `vector` (which must be empty) reserve room for `count` elements, advised onto huge
/// pages when large. Call it before writing the elements (large allocations come straight
/// from mmap, untouched).
template <class T>
void reserve_on_huge_pages(std::vector<T>& vector, std::size_t count) {
    vector.reserve(count);
    advise_huge_pages(vector.data(), count * sizeof(T));
}

/// A copy of `elements` in a vector prepared by reserve_on_huge_pages().
template <class T>
std::vector<T> copy_on_huge_pages(std::span<const T> elements) {
    std::vector<T> copy;
    reserve_on_huge_pages(copy, elements.size());
    copy.assign(elements.begin(), elements.end());
    return copy;
}

}  // namespace rebraid
