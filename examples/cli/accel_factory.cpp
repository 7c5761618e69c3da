#include "accel_factory.h"

#include <array>

#include "embree_glue/embree_reference.h"
#include "rebraid/error.h"

namespace rebraid::cli {

namespace {

template <class AccelType>
std::unique_ptr<Accel> build_as(const Scene& scene) {
    return std::make_unique<AccelType>(scene);
}

// Adding a structure to the command line is one line here.
constexpr std::array kAccelTable{
    AccelEntry{"embree-flat", "Embree, every instance's triangles in one world-space scene",
               &build_as<glue::EmbreeFlatAccel>},
    AccelEntry{"embree-instanced", "Embree, one scene per mesh plus one instance per instance",
               &build_as<glue::EmbreeInstancedAccel>},
};

}  // namespace

std::span<const AccelEntry> accel_entries() {
    return kAccelTable;
}

std::vector<std::string> accel_names() {
    std::vector<std::string> names;
    for (const AccelEntry& entry : accel_entries()) names.emplace_back(entry.name);
    return names;
}

std::string accel_names_joined() {
    std::string joined;
    for (const AccelEntry& entry : accel_entries()) {
        if (!joined.empty()) joined += ", ";
        joined += entry.name;
    }
    return joined;
}

const AccelEntry& find_accel(std::string_view name) {
    for (const AccelEntry& entry : accel_entries())
        if (entry.name == name) return entry;
    throw Error("unknown accel '" + std::string(name) + "'; valid names: " + accel_names_joined());
}

std::unique_ptr<Accel> build_accel(std::string_view name, const Scene& scene) {
    return find_accel(name).build(scene);
}

}  // namespace rebraid::cli
