#pragma once

#include <stdexcept>
#include <string>

namespace rebraid {

/// The one exception type the library throws at its API boundaries. The message names the
/// call, the object and the offending value, so a user can act on it without a debugger.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace rebraid

/// Checks that are only worth their cost in debug builds (hot loops); compiled out with NDEBUG.
#ifdef NDEBUG
#define REBRAID_ASSERT(condition) ((void)0)
#else
#include <cassert>
#define REBRAID_ASSERT(condition) assert(condition)
#endif
