#pragma once

// Forwarding to the real Embree from functions that take Embree's names (the interposer, the
// preload library's ray queries).

#include <dlfcn.h>

#include <type_traits>
#include <utility>

namespace rebraid::glue {

/// The next definition of `name` after the one calling: libembree3's.
template <typename Function>
Function* next_definition(const char* name) {
    return reinterpret_cast<Function*>(dlsym(RTLD_NEXT, name));
}

/// Calls the real function. Should Embree not be found (only a broken link can cause that),
/// behaves like a call Embree refused: a null or zero result and no effect.
template <typename Result, typename... Parameters, typename... Arguments>
Result call_real(Result (*function)(Parameters...), Arguments&&... arguments) {
    if (function == nullptr) {
        if constexpr (std::is_void_v<Result>)
            return;
        else
            return Result{};
    }
    return function(std::forward<Arguments>(arguments)...);
}

}  // namespace rebraid::glue
