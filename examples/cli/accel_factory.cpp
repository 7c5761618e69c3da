#include "accel_factory.h"

#include <array>
#include <cmath>
#include <string>

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

constexpr std::array kOpeningRules{OpeningRule::extent, OpeningRule::sah, OpeningRule::overlap};
constexpr std::array kBRefBoundsRules{BRefBoundsRule::transformed_box,
                                      BRefBoundsRule::transformed_children,
                                      BRefBoundsRule::transformed_vertices};

/// The structure's own name: `spec` up to its first ':'.
std::string_view base_name(std::string_view spec) {
    return spec.substr(0, spec.find(':'));
}

const AccelEntry& find_entry(std::string_view name) {
    for (const AccelEntry& entry : accel_entries())
        if (entry.name == name) return entry;
    throw Error("unknown accel '" + std::string(name) + "'; valid names: " + accel_names_joined());
}

/// One KEY=VALUE of a variant suffix applied to `options`.
void apply_variant_setting(std::string_view spec, std::string_view key, std::string_view value,
                           AccelOptions& options) {
    const auto fail = [&](const std::string& why) -> void {
        throw Error("accel '" + std::string(spec) + "': " + std::string(key) + "=" +
                    std::string(value) + ": " + why);
    };
    const auto number = [&]() {
        const std::string text(value);
        std::size_t used = 0;
        float parsed = 0.0f;
        try {
            parsed = std::stof(text, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != text.size() || text.empty() || !std::isfinite(parsed))
            fail("not a finite number");
        return parsed;
    };
    const auto one_of = [&](auto names, auto& field) {
        for (const auto& [name, choice] : names)
            if (name == value) {
                field = choice;
                return;
            }
        std::string valid;
        for (const auto& [name, choice] : names)
            valid += (valid.empty() ? "" : ", ") + std::string(name);
        fail("valid values: " + valid);
    };
    RebraidSettings& rebraid = options.rebraid;
    if (key == "object-builder") {
        for (ObjectBuilderKind kind : object_builder_kinds())
            if (object_builder_name(kind) == value) {
                options.object_builder = kind;
                return;
            }
        fail("not an object builder");
    } else if (key == "open-threshold") {
        rebraid.open_threshold = number();
    } else if (key == "budget-factor") {
        rebraid.budget_factor = number();
    } else if (key == "primitives-per-bref") {
        rebraid.primitives_per_bref = number();
    } else if (key == "instance-entry-cost") {
        rebraid.instance_entry_cost = number();
    } else if (key == "estimate-levels") {
        const float levels = number();
        if (levels < 0.0f || levels > 8.0f || levels != std::floor(levels))
            fail("not a whole number in [0, 8]");
        rebraid.estimate_levels = std::uint32_t(levels);
    } else if (key == "budget-doublings") {
        const float doublings = number();
        if (doublings < 0.0f || doublings > 16.0f || doublings != std::floor(doublings))
            fail("not a whole number in [0, 16]");
        rebraid.budget_doublings = std::uint32_t(doublings);
    } else if (key == "overlap-threshold") {
        rebraid.overlap_threshold = number();
    } else if (key == "budget-rule") {
        one_of(std::array{std::pair{std::string_view("instances"), BudgetRule::per_instance},
                          std::pair{std::string_view("primitives"), BudgetRule::per_primitive}},
               rebraid.budget_rule);
    } else if (key == "bref-bounds") {
        std::array<std::pair<std::string_view, BRefBoundsRule>, kBRefBoundsRules.size()> names;
        for (std::size_t i = 0; i < names.size(); ++i)
            names[i] = {bref_bounds_rule_name(kBRefBoundsRules[i]), kBRefBoundsRules[i]};
        one_of(names, rebraid.bounds_rule);
    } else if (key == "opening") {
        std::array<std::pair<std::string_view, OpeningRule>, kOpeningRules.size()> names;
        for (std::size_t i = 0; i < names.size(); ++i)
            names[i] = {opening_rule_name(kOpeningRules[i]), kOpeningRules[i]};
        one_of(names, rebraid.opening_rule);
    } else if (key == "open-leaves") {
        one_of(std::array{std::pair{std::string_view("1"), true},
                          std::pair{std::string_view("0"), false},
                          std::pair{std::string_view("true"), true},
                          std::pair{std::string_view("false"), false}},
               rebraid.open_leaves);
    } else {
        throw Error("accel '" + std::string(spec) + "': unknown setting '" + std::string(key) +
                    "'; valid keys: " + std::string(kAccelVariantKeys));
    }
}

}  // namespace

std::string_view opening_rule_name(OpeningRule rule) {
    switch (rule) {
        case OpeningRule::extent:
            return "extent";
        case OpeningRule::sah:
            return "sah";
        case OpeningRule::overlap:
            return "overlap";
    }
    return "unknown";
}

std::span<const OpeningRule> opening_rules() {
    return kOpeningRules;
}

std::string_view bref_bounds_rule_name(BRefBoundsRule rule) {
    switch (rule) {
        case BRefBoundsRule::transformed_box:
            return "box";
        case BRefBoundsRule::transformed_children:
            return "children";
        case BRefBoundsRule::transformed_vertices:
            return "vertices";
    }
    return "unknown";
}

std::span<const BRefBoundsRule> bref_bounds_rules() {
    return kBRefBoundsRules;
}

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

AccelVariant parse_accel_variant(std::string_view spec, const AccelOptions& base) {
    AccelVariant variant{&find_entry(base_name(spec)), base, std::string(spec)};
    std::size_t start = spec.find(':');
    while (start != std::string_view::npos) {
        const std::size_t end = spec.find(':', start + 1);
        const std::string_view setting = spec.substr(
            start + 1, end == std::string_view::npos ? std::string_view::npos : end - start - 1);
        const std::size_t equals = setting.find('=');
        if (equals == std::string_view::npos)
            throw Error("accel '" + std::string(spec) + "': setting '" + std::string(setting) +
                        "' is not KEY=VALUE");
        apply_variant_setting(spec, setting.substr(0, equals), setting.substr(equals + 1),
                              variant.options);
        start = end;
    }
    variant.options.rebraid.validate();
    return variant;
}

const AccelEntry& find_accel(std::string_view spec) {
    return *parse_accel_variant(spec).entry;
}

std::unique_ptr<Accel> build_accel(std::string_view spec, const Scene& scene,
                                   const AccelOptions& options) {
    options.rebraid.validate();
    const AccelVariant variant = parse_accel_variant(spec, options);
    return variant.entry->build(scene, variant.options);
}

}  // namespace rebraid::cli
