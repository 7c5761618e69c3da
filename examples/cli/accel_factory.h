#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rebraid/accel.h"
#include "rebraid/scene.h"

namespace rebraid::cli {

/// The structure every command builds when `--accel` is not given.
inline constexpr std::string_view kDefaultAccelName = "embree-flat";

/// One structure the command line can build: its `--accel` name and how to build it.
struct AccelEntry {
    std::string_view name;
    std::string_view description;  ///< one line for `--help`
    std::unique_ptr<Accel> (*build)(const Scene& scene);
};

/// Every structure `--accel` accepts, in the order `--help` lists them.
std::span<const AccelEntry> accel_entries();

/// The valid `--accel` names, in table order.
std::vector<std::string> accel_names();

/// The valid names joined with ", " (for help texts and error messages).
std::string accel_names_joined();

/// The entry called `name`; throws rebraid::Error listing the valid names when there is none.
/// Commands call this before loading a scene, so a typo fails fast.
const AccelEntry& find_accel(std::string_view name);

/// Builds the structure called `name` over `scene`. The scene must outlive the result.
std::unique_ptr<Accel> build_accel(std::string_view name, const Scene& scene);

}  // namespace rebraid::cli
