#pragma once

#include <functional>
#include <optional>
#include <string>

#include "embree_glue/dropin/embree_accel.h"

namespace rebraid::glue {

/// What the preload library does, read from the environment when it is loaded.
struct PreloadSettings {
    /// REBRAID_PRELOAD (default 1): 0 leaves every scene to Embree.
    bool is_enabled = true;
    /// REBRAID_PRELOAD_LOG (default 0): 1 prints one line per decision on stderr.
    bool is_logging = false;
    /// The structure built for each served scene: REBRAID_ACCEL, in the `rebraid` command's
    /// `--accel` grammar (`rebraid:opening=extent:object-builder=embree-high`).
    EmbreeAccelSettings accel{};
};

/// Reads a variable: its value, or nothing when it is not set.
using EnvironmentReader = std::function<std::optional<std::string>(const std::string& name)>;

/// The settings the environment asks for. Throws rebraid::Error naming the variable and the
/// value for a value it does not accept.
PreloadSettings read_preload_settings(const EnvironmentReader& environment);

/// The process environment (getenv); a variable set to the empty string reads as unset.
std::optional<std::string> process_environment(const std::string& name);

}  // namespace rebraid::glue
