#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace rebraid {

/// Arrays smaller than this stay on ordinary pages: they fit the TLB anyway.
inline constexpr std::size_t kHugePageMinBytes = std::size_t(4) << 20;

/// Makes `vector` (which must be empty) reserve room for `count` elements and asks the OS to
/// back that room with transparent huge pages (Linux madvise MADV_HUGEPAGE; elsewhere it only
/// reserves). Why: rays traced in random order touch BVH nodes and triangles all over arrays
/// of tens of megabytes, and with 4 KB pages nearly every such access also misses the TLB;
/// 2 MB pages remove most of those page walks. The advice only helps memory not touched yet,
/// so call this before writing the elements (large allocations come straight from mmap).
template <class T>
void reserve_on_huge_pages(std::vector<T>& vector, std::size_t count) {
    vector.reserve(count);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    const std::size_t bytes = count * sizeof(T);
    if (bytes < kHugePageMinBytes) return;
    constexpr std::uintptr_t kPage = 4096;
    const auto begin = reinterpret_cast<std::uintptr_t>(vector.data());
    const std::uintptr_t first = (begin + kPage - 1) & ~(kPage - 1);
    const std::uintptr_t last = (begin + bytes) & ~(kPage - 1);
    // Best effort: without THP support the call fails and the pages are ordinary ones.
    if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#endif
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
