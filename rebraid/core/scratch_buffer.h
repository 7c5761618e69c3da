#pragma once

#include <cstddef>
#include <new>
#include <span>
#include <type_traits>

#include "rebraid/core/huge_pages.h"

namespace rebraid {

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
          alignment_(count * sizeof(T) >= kHugePageMinBytes ? kHugePageAlignment
                                                            : std::align_val_t(alignof(T))) {
        if (count_ == 0) return;
        data_ = static_cast<T*>(::operator new(count_ * sizeof(T), alignment_));
        advise_huge_pages(data_, count_ * sizeof(T));
    }
    ~ScratchBuffer() {
        // The unsized form: the sized one needs -fsized-deallocation under clang.
        if (data_) ::operator delete(data_, alignment_);
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
