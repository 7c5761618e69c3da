#pragma once

#include <cstddef>
#include <cstdint>
#include <new>
#include <span>
#include <type_traits>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace rebraid {

/// Buffers at least this large are advised onto transparent huge pages.
inline constexpr std::size_t kBuildHugePageMinBytes = std::size_t(4) << 20;

/// Asks the OS to back the whole 4 KB pages of [data, data + bytes) with transparent huge
/// pages (Linux madvise MADV_HUGEPAGE; a no-op elsewhere or for small buffers). Why: a build
/// writes tens of megabytes of fresh memory (scratch space, node arrays), and with 4 KB pages
/// every first touch is a page fault, thousands of cycles each (more under virtualisation):
/// profiles of 1.5M-triangle builds spent a fifth of their time in the kernel. Only helps
/// memory not touched yet. Best effort: without THP support nothing changes.
inline void advise_huge_pages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (bytes < kBuildHugePageMinBytes) return;
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

/// Uninitialised storage for `count` elements of a trivially copyable T: the builder's
/// scratch space. Nothing is written on construction (C++20 creates the elements implicitly
/// when they are first written), so the pages are first touched by whichever (parallel) pass
/// writes them, not by one thread here; large buffers are aligned to 2 MB and advised onto
/// huge pages.
template <class T>
class ScratchBuffer {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

public:
    explicit ScratchBuffer(std::size_t count)
        : count_(count),
          alignment_(count * sizeof(T) >= kBuildHugePageMinBytes ? kHugePageAlignment
                                                                 : std::align_val_t(alignof(T))) {
        if (count_ == 0) return;
        data_ = static_cast<T*>(::operator new(count_ * sizeof(T), alignment_));
        advise_huge_pages(data_, count_ * sizeof(T));
    }
    ~ScratchBuffer() {
        if (data_) ::operator delete(data_, count_ * sizeof(T), alignment_);
    }
    ScratchBuffer(const ScratchBuffer&) = delete;
    ScratchBuffer& operator=(const ScratchBuffer&) = delete;

    std::span<T> span() const { return {data_, count_}; }

private:
    static constexpr std::align_val_t kHugePageAlignment{std::size_t(2) << 20};

    T* data_ = nullptr;
    std::size_t count_ = 0;
    std::align_val_t alignment_;
};

}  // namespace rebraid
