#include "embree_glue/preload/preload_settings.h"

#include <cstdlib>

#include "accel_factory.h"
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

/// EmbreeAccel's settings from the `rebraid` command's `--accel` grammar,
/// `rebraid[:KEY=VALUE]...` (examples/cli/accel_factory.h); only `rebraid` is an EmbreeAccel.
EmbreeAccelSettings accel_settings(const std::string& spec) {
    const cli::AccelVariant variant = [&] {
        try {
            // On top of EmbreeAccel's defaults (object spaces kept), not the command's.
            cli::AccelOptions base;
            base.rebraid = EmbreeAccelSettings{}.rebraid;
            return cli::parse_accel_variant(spec, base);
        } catch (const Error& error) {
            throw Error(std::string("REBRAID_ACCEL=") + spec + ": " + error.what());
        }
    }();
    if (variant.entry->name != "rebraid")
        throw Error("REBRAID_ACCEL=" + spec + ": the preload builds rebraid only (with " +
                    "settings: rebraid:KEY=VALUE...)");
    EmbreeAccelSettings settings;
    settings.rebraid = variant.options.rebraid;
    settings.own_builder.spatial_split_budget = variant.options.spatial_split_budget;
    switch (variant.options.object_builder) {
        case cli::ObjectBuilderKind::own:
            settings.object_builder = EmbreeAccelObjectBuilder::own;
            break;
        case cli::ObjectBuilderKind::embree_high:
            settings.object_builder = EmbreeAccelObjectBuilder::embree;
            settings.embree_builder.quality = EmbreeBuildQuality::high;
            settings.embree_builder.can_split_triangles = true;
            break;
        case cli::ObjectBuilderKind::embree_medium:
            settings.object_builder = EmbreeAccelObjectBuilder::embree;
            settings.embree_builder.quality = EmbreeBuildQuality::medium;
            break;
    }
    return settings;
}

}  // namespace

PreloadSettings read_preload_settings(const EnvironmentReader& environment) {
    PreloadSettings settings;
    settings.is_enabled = read_switch(environment, "REBRAID_PRELOAD", true);
    settings.is_logging = read_switch(environment, "REBRAID_PRELOAD_LOG", false);
    if (const std::optional<std::string> spec = environment("REBRAID_ACCEL"))
        settings.accel = accel_settings(*spec);
    settings.accel.validate();
    return settings;
}

std::optional<std::string> process_environment(const std::string& name) {
    const char* value = std::getenv(name.c_str());
    // Set but empty counts as unset: shells and launchers pass `NAME=` for a setting they
    // leave at its default.
    if (value == nullptr || *value == '\0') return std::nullopt;
    return std::string(value);
}

}  // namespace rebraid::glue
