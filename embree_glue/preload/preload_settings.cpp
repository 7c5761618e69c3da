#include "embree_glue/preload/preload_settings.h"

#include <cstdlib>

#include "rebraid/core/error.h"

namespace rebraid::glue {
namespace {

/// "0" or "1"; `fallback` when unset.
bool read_switch(const EnvironmentReader& environment, const std::string& name, bool fallback) {
    const std::optional<std::string> value = environment(name);
    if (!value) return fallback;
    if (*value == "1") return true;
    if (*value == "0") return false;
    throw Error(name + "=" + *value + ": expected 0 or 1");
}

}  // namespace

PreloadSettings read_preload_settings(const EnvironmentReader& environment) {
    PreloadSettings settings;
    settings.is_enabled = read_switch(environment, "REBRAID_PRELOAD", true);
    settings.is_logging = read_switch(environment, "REBRAID_PRELOAD_LOG", false);
    settings.accel.validate();
    return settings;
}

std::optional<std::string> process_environment(const std::string& name) {
    const char* value = std::getenv(name.c_str());
    if (value == nullptr) return std::nullopt;
    return std::string(value);
}

}  // namespace rebraid::glue
