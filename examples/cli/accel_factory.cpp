#include "accel_factory.h"

#include <array>

#include "embree_glue/embree_bvh_builder.h"
#include "embree_glue/embree_reference.h"
#include "rebraid/error.h"
#include "rebraid/flat_accel.h"
#include "rebraid/instanced_accel.h"
#include "rebraid/rebraid_builder.h"

namespace rebraid::cli {

namespace {

template <class AccelType>
std::unique_ptr<Accel> build_without_options(const Scene& scene, const AccelOptions& /*options*/) {
    return std::make_unique<AccelType>(scene);
}

std::unique_ptr<Accel> build_two_level(const Scene& scene, const AccelOptions& options) {
    return std::make_unique<InstancedAccel>(
        build_two_level_accel(scene, make_object_builder(options.object_builder)));
}

std::unique_ptr<Accel> build_rebraid(const Scene& scene, const AccelOptions& options) {
    return std::make_unique<InstancedAccel>(
        build_rebraid_accel(scene, make_object_builder(options.object_builder), options.rebraid));
}

// Adding a structure to the command line is one line here.
constexpr std::array kAccelTable{
    AccelEntry{"embree-flat", "Embree, every instance's triangles in one world-space scene",
               &build_without_options<glue::EmbreeFlatAccel>},
    AccelEntry{"embree-instanced", "Embree, one scene per mesh plus one instance per instance",
               &build_without_options<glue::EmbreeInstancedAccel>},
    AccelEntry{"flat", "one BVH over every instance's triangles in world space (no instancing)",
               &build_without_options<FlatAccel>},
    AccelEntry{"twolevel", "object BVHs plus a binned-SAH top level over the instances",
               &build_two_level, true},
    AccelEntry{"rebraid", "object BVHs plus a re-braided top level (Benthin et al. 2017)",
               &build_rebraid, true},
};

constexpr std::array kObjectBuilderKinds{ObjectBuilderKind::own, ObjectBuilderKind::embree_high,
                                         ObjectBuilderKind::embree_medium};

}  // namespace

std::string_view object_builder_name(ObjectBuilderKind kind) {
    switch (kind) {
        case ObjectBuilderKind::own:
            return "own";
        case ObjectBuilderKind::embree_high:
            return "embree-high";
        case ObjectBuilderKind::embree_medium:
            return "embree-medium";
    }
    return "unknown";
}

std::span<const ObjectBuilderKind> object_builder_kinds() {
    return kObjectBuilderKinds;
}

ObjectBvhBuilder make_object_builder(ObjectBuilderKind kind) {
    switch (kind) {
        case ObjectBuilderKind::own:
            return own_object_bvh_builder();
        case ObjectBuilderKind::embree_high:
            // High quality differs from medium only through spatial splits (see
            // EmbreeBvhBuilderSettings), so "embree-high" means them.
            return glue::embree_object_bvh_builder(
                {.quality = glue::EmbreeBuildQuality::high, .can_split_triangles = true});
        case ObjectBuilderKind::embree_medium:
            return glue::embree_object_bvh_builder({.quality = glue::EmbreeBuildQuality::medium});
    }
    throw Error("make_object_builder: unknown object builder " +
                std::to_string(static_cast<int>(kind)));
}

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

std::unique_ptr<Accel> build_accel(std::string_view name, const Scene& scene,
                                   const AccelOptions& options) {
    options.rebraid.validate();
    return find_accel(name).build(scene, options);
}

}  // namespace rebraid::cli
