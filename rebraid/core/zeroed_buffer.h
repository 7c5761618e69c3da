#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <span>
#include <type_traits>

#include "rebraid/core/huge_pages.h"

namespace rebraid {

/// Storage for `count` elements of a trivially copyable T whose bytes all start at zero,
/// without writing them: large blocks come from calloc as fresh, already zeroed pages, so
/// only the pages a build touches are ever faulted in. For per-slot arrays of re-braiding
/// builds, sized for the whole BRef budget of which a build often uses a small part (a
/// vector would write every element first: at a million instances 100 MB of zeros per build).
template <class T>
class ZeroedBuffer {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

public:
    explicit ZeroedBuffer(std::size_t count) : count_(count) {
        if (count_ == 0) return;
        data_ = static_cast<T*>(std::calloc(count_, sizeof(T)));
        if (data_ == nullptr) throw std::bad_alloc();
        advise_huge_pages(data_, count_ * sizeof(T));
    }
    ~ZeroedBuffer() { std::free(data_); }
    ZeroedBuffer(const ZeroedBuffer&) = delete;
    ZeroedBuffer& operator=(const ZeroedBuffer&) = delete;

    std::span<T> span() const { return {data_, count_}; }
    T& operator[](std::size_t i) const { return data_[i]; }

private:
    T* data_ = nullptr;
    std::size_t count_ = 0;
};

}  // namespace rebraid
