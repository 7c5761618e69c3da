#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <utility>

namespace rebraid::glue {

/// Storage whose object is never destroyed: the application may call Embree from its own
/// static destructors, which can run after a static object of ours would be gone.
template <typename T>
class NeverDestroyed {
public:
    template <typename... Arguments>
    explicit NeverDestroyed(Arguments&&... arguments) {
        std::construct_at(reinterpret_cast<T*>(storage_), std::forward<Arguments>(arguments)...);
    }
    NeverDestroyed(const NeverDestroyed&) = delete;
    NeverDestroyed& operator=(const NeverDestroyed&) = delete;

    T& get() { return *std::launder(reinterpret_cast<T*>(storage_)); }

private:
    alignas(T) std::byte storage_[sizeof(T)];
};

}  // namespace rebraid::glue
