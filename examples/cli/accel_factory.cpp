#include "accel_factory.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "embree_glue/reference/embree_bvh_builder.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"

namespace rebraid::cli {

namespace {

/// The triangle test `options` asks for: watertight in robust mode, as Embree's robust mode.
TriangleTest triangle_test_of(const AccelOptions& options) {
    return options.is_robust ? TriangleTest::watertight : TriangleTest::moller;
}

/// The own builder's settings `options` asks for.
BuildSettings own_build_settings(const AccelOptions& options) {
    BuildSettings settings = static_object_build_settings();
    settings.spatial_split_budget = options.spatial_split_budget;
    return settings;
}

std::unique_ptr<Accel> build_flat(const Scene& scene, const AccelOptions& options) {
    auto accel = std::make_unique<FlatAccel>(scene, own_build_settings(options));
    accel->set_triangle_test(triangle_test_of(options));
    return accel;
}

template <class EmbreeAccelType>
std::unique_ptr<Accel> build_embree(const Scene& scene, const AccelOptions& options) {
    glue::EmbreeReferenceSettings settings;
    settings.is_robust = options.is_robust;
    return std::make_unique<EmbreeAccelType>(scene, settings);
}

std::unique_ptr<Accel> build_two_level(const Scene& scene, const AccelOptions& options) {
    auto accel = std::make_unique<InstancedAccel>(build_two_level_accel(
        scene, make_object_builder(options.object_builder, own_build_settings(options))));
    accel->set_triangle_test(triangle_test_of(options));
    return accel;
}

std::unique_ptr<Accel> build_rebraid(const Scene& scene, const AccelOptions& options) {
    auto accel = std::make_unique<InstancedAccel>(build_rebraid_accel(
        scene, make_object_builder(options.object_builder, own_build_settings(options)),
        options.rebraid));
    accel->set_triangle_test(triangle_test_of(options));
    return accel;
}

// Adding a structure to the command line is one line here.
constexpr std::array kAccelTable{
    AccelEntry{"embree-flat", "Embree, every instance's triangles in one world-space scene",
               &build_embree<glue::EmbreeFlatAccel>, false, false, true, false},
    AccelEntry{"embree-instanced", "Embree, one scene per mesh plus one instance per instance",
               &build_embree<glue::EmbreeInstancedAccel>, false, false, true, false},
    AccelEntry{"flat", "one BVH over every instance's triangles in world space (no instancing)",
               &build_flat, false, false, true, true},
    AccelEntry{"twolevel", "object BVHs plus a binned-SAH top level over the instances",
               &build_two_level, true, false, true, true},
    AccelEntry{"rebraid", "object BVHs plus a re-braided top level (Benthin et al. 2017)",
               &build_rebraid, true, true, true, true},
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

/// The VALUE of one KEY=VALUE of a variant suffix, with the readings the keys share; each
/// throws rebraid::Error naming the spec, the key and the value when the value does not fit.
class VariantValue {
public:
    VariantValue(std::string_view spec, std::string_view key, std::string_view value)
        : spec_(spec), key_(key), value_(value) {}

    [[noreturn]] void fail(const std::string& why) const {
        throw Error("accel '" + std::string(spec_) + "': " + std::string(key_) + "=" +
                    std::string(value_) + ": " + why);
    }

    /// The value as a finite float.
    float number() const {
        const std::string text(value_);
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
    }

    /// The value as a whole number in [0, `max`].
    std::uint32_t whole_number(std::uint32_t max) const {
        const float parsed = number();
        if (parsed < 0.0f || parsed > float(max) || parsed != std::floor(parsed))
            fail("not a whole number in [0, " + std::to_string(max) + "]");
        return std::uint32_t(parsed);
    }

    /// The choice `names` gives the value; fails with `why_none`, or by default the list of
    /// valid values, when it names none.
    template <class Choice>
    Choice choice(std::span<const std::pair<std::string_view, Choice>> names,
                  const std::string& why_none = {}) const {
        for (const auto& [name, option] : names)
            if (name == value_) return option;
        if (!why_none.empty()) fail(why_none);
        std::string valid;
        for (const auto& name_and_choice : names)
            valid += (valid.empty() ? "" : ", ") + std::string(name_and_choice.first);
        fail("valid values: " + valid);
    }

private:
    std::string_view spec_, key_, value_;
};

/// What one variant key does: sets AccelOptions from its value, and tells whether two sets of
/// options agree on the setting it sets.
struct Setting {
    std::function<void(const VariantValue&, AccelOptions&)> apply;
    std::function<bool(const AccelOptions&, const AccelOptions&)> is_same;
};

template <class Field>
std::function<bool(const AccelOptions&, const AccelOptions&)> same_field(
    Field RebraidSettings::*field) {
    return [field](const AccelOptions& a, const AccelOptions& b) {
        return a.rebraid.*field == b.rebraid.*field;
    };
}

Setting real_number(float RebraidSettings::*field) {
    return {[field](const VariantValue& value, AccelOptions& options) {
                options.rebraid.*field = value.number();
            },
            same_field(field)};
}

Setting whole_number(std::uint32_t RebraidSettings::*field, std::uint32_t max) {
    return {[field, max](const VariantValue& value, AccelOptions& options) {
                options.rebraid.*field = value.whole_number(max);
            },
            same_field(field)};
}

template <class Choice>
Setting named_choice(Choice RebraidSettings::*field,
                     std::vector<std::pair<std::string_view, Choice>> names) {
    return {[field, names = std::move(names)](const VariantValue& value, AccelOptions& options) {
                options.rebraid.*field = value.choice<Choice>(names);
            },
            same_field(field)};
}

/// Each of `choices` under the name `name_of` gives it, in the order of `choices`.
template <class Choice, std::size_t N>
std::vector<std::pair<std::string_view, Choice>> named(const std::array<Choice, N>& choices,
                                                       std::string_view (*name_of)(Choice)) {
    std::vector<std::pair<std::string_view, Choice>> names;
    for (const Choice choice : choices) names.emplace_back(name_of(choice), choice);
    return names;
}

struct VariantKey {
    std::string_view key;
    Setting setting;
};

/// Every key a variant suffix accepts (accel_variant_keys() lists them for help texts): adding
/// one is one line here.
const std::vector<VariantKey>& variant_keys() {
    using Settings = RebraidSettings;
    static const std::vector<VariantKey> keys{
        {"object-builder",
         {[](const VariantValue& value, AccelOptions& options) {
              options.object_builder = value.choice<ObjectBuilderKind>(
                  named(kObjectBuilderKinds, object_builder_name), "not an object builder");
          },
          [](const AccelOptions& a, const AccelOptions& b) {
              return a.object_builder == b.object_builder;
          }}},
        {"open-threshold", real_number(&Settings::open_threshold)},
        {"budget-factor", real_number(&Settings::budget_factor)},
        {"budget-rule",
         named_choice(&Settings::budget_rule, {{"instances", BudgetRule::per_instance},
                                               {"primitives", BudgetRule::per_primitive},
                                               {"larger", BudgetRule::larger}})},
        {"primitives-per-bref", real_number(&Settings::primitives_per_bref)},
        {"bref-bounds",
         named_choice(&Settings::bounds_rule, named(kBRefBoundsRules, bref_bounds_rule_name))},
        {"opening", named_choice(&Settings::opening_rule, named(kOpeningRules, opening_rule_name))},
        {"open-leaves",
         named_choice(&Settings::open_leaves,
                      {{"1", true}, {"0", false}, {"true", true}, {"false", false}})},
        {"instance-entry-cost", real_number(&Settings::instance_entry_cost)},
        {"estimate-levels", whole_number(&Settings::estimate_levels, 8)},
        {"world-space-estimate-levels", whole_number(&Settings::world_space_estimate_levels, 8)},
        {"estimate-max-brefs", whole_number(&Settings::estimate_max_brefs, 1u << 30)},
        {"estimate-give-up", whole_number(&Settings::estimate_give_up, 64)},
        {"estimate-give-up-brefs", whole_number(&Settings::estimate_give_up_brefs, 1u << 30)},
        {"require-overlap",
         named_choice(&Settings::require_overlap,
                      {{"1", true}, {"0", false}, {"true", true}, {"false", false}})},
        {"overlap-threshold", real_number(&Settings::overlap_threshold)},
        {"budget-doublings", whole_number(&Settings::budget_doublings, kMaxBudgetDoublings)},
        {"rebuild-tree",
         named_choice(&Settings::rebuild_tree,
                      {{"1", true}, {"0", false}, {"true", true}, {"false", false}})},
        {"world-single",
         named_choice(&Settings::world_space_single_instances,
                      {{"1", true}, {"0", false}, {"true", true}, {"false", false}})},
        {"world-copies", real_number(&Settings::world_space_copy_budget)},
        {"merge-world",
         named_choice(&Settings::merge_world_space,
                      {{"1", true}, {"0", false}, {"true", true}, {"false", false}})},
        {"merge-placed",
         named_choice(&Settings::merge_placed_instances,
                      {{"1", true}, {"0", false}, {"true", true}, {"false", false}})},
        {"merge-placed-budget", real_number(&Settings::merge_placed_node_budget)},
        {"items-out-of-line", real_number(&Settings::merge_items_out_of_line_area_share)},
        {"world-tree", named_choice(&Settings::world_tree,
                                    {{"1", true}, {"0", false}, {"true", true}, {"false", false}})},
        {"world-tree-budget", real_number(&Settings::world_tree_triangle_budget)},
        {"world-tree-instances", whole_number(&Settings::world_tree_max_instances, 1u << 27)},
        {"world-tree-triangles", whole_number(&Settings::world_tree_max_triangles, 1u << 31)},
        {"world-tree-splits", real_number(&Settings::world_tree_spatial_split_budget)},
        {"top-collapse",
         {[](const VariantValue& value, AccelOptions& options) {
              options.rebraid.build.collapse =
                  value.choice<NodeCollapse>(std::vector<std::pair<std::string_view, NodeCollapse>>{
                      {"greedy", NodeCollapse::greedy}, {"optimal", NodeCollapse::optimal}});
          },
          [](const AccelOptions& a, const AccelOptions& b) {
              return a.rebraid.build.collapse == b.rebraid.build.collapse;
          }}},
        {"budget-search-min-use", real_number(&Settings::budget_search_min_use)},
        {"budget-search-extra-gain", real_number(&Settings::budget_search_extra_gain)},
        {"robust",
         {[](const VariantValue& value, AccelOptions& options) {
              options.is_robust = value.choice<bool>(std::vector<std::pair<std::string_view, bool>>{
                  {"1", true}, {"0", false}, {"true", true}, {"false", false}});
          },
          [](const AccelOptions& a, const AccelOptions& b) { return a.is_robust == b.is_robust; }}},
        {"spatial-splits",
         {[](const VariantValue& value, AccelOptions& options) {
              options.spatial_split_budget = value.number();
              if (!(options.spatial_split_budget >= 0.0f && options.spatial_split_budget <= 4.0f))
                  value.fail("not a fraction of the triangles in [0, 4]");
          },
          [](const AccelOptions& a, const AccelOptions& b) {
              return a.spatial_split_budget == b.spatial_split_budget;
          }}},
    };
    return keys;
}

constexpr std::string_view kObjectBuilderKey = "object-builder";
constexpr std::string_view kRobustKey = "robust";
constexpr std::string_view kSpatialSplitsKey = "spatial-splits";

/// Which structures a variant key changes: AccelEntry's flag for it.
bool AccelEntry::*structures_using(std::string_view key) {
    if (key == kObjectBuilderKey) return &AccelEntry::has_object_bvhs;
    if (key == kRobustKey) return &AccelEntry::has_robust_mode;
    if (key == kSpatialSplitsKey) return &AccelEntry::has_own_triangle_bvhs;
    return &AccelEntry::has_rebraid_settings;
}

/// The names of the structures for which `uses` holds, for messages ("twolevel or rebraid").
std::string names_of_structures_using(bool AccelEntry::*uses) {
    std::string names;
    for (const AccelEntry& entry : accel_entries())
        if (entry.*uses) names += (names.empty() ? "" : " or ") + std::string(entry.name);
    return names;
}

/// One KEY=VALUE of a variant suffix applied to `options`; a key the structure does not use
/// is an error rather than a variant identical to the plain structure.
void apply_variant_setting(std::string_view spec, const AccelEntry& entry, std::string_view key,
                           std::string_view value, AccelOptions& options) {
    for (const VariantKey& variant_key : variant_keys()) {
        if (variant_key.key != key) continue;
        bool AccelEntry::*uses = structures_using(key);
        if (!(entry.*uses))
            throw Error("accel '" + std::string(spec) + "': " + std::string(entry.name) +
                        " does not use " + std::string(key) + "; it is a setting of " +
                        names_of_structures_using(uses));
        return variant_key.setting.apply(VariantValue(spec, key, value), options);
    }
    throw Error("accel '" + std::string(spec) + "': unknown setting '" + std::string(key) +
                "'; valid keys: " + accel_variant_keys());
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

ObjectBvhBuilder make_object_builder(ObjectBuilderKind kind, const BuildSettings& own_settings) {
    switch (kind) {
        case ObjectBuilderKind::own:
            return own_object_bvh_builder(own_settings);
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
        apply_variant_setting(spec, *variant.entry, setting.substr(0, equals),
                              setting.substr(equals + 1), variant.options);
        start = end;
    }
    try {
        variant.options.rebraid.validate();
    } catch (const Error& error) {
        // Names the --accel text too, since the value may come from it.
        throw Error("accel '" + std::string(spec) + "': " + error.what());
    }
    return variant;
}

std::string accel_variant_keys() {
    std::string keys;
    for (const VariantKey& variant_key : variant_keys())
        keys += (keys.empty() ? "" : ", ") + std::string(variant_key.key);
    return keys;
}

const AccelEntry& find_accel(std::string_view spec) {
    return *parse_accel_variant(spec).entry;
}

void check_variants_differ(std::span<const AccelVariant> variants) {
    for (std::size_t i = 0; i < variants.size(); ++i)
        for (std::size_t j = i + 1; j < variants.size(); ++j) {
            const AccelVariant &a = variants[i], &b = variants[j];
            if (a.entry != b.entry) continue;
            bool is_same = true;
            for (const VariantKey& variant_key : variant_keys()) {
                const bool is_used = a.entry->*structures_using(variant_key.key);
                if (is_used && !variant_key.setting.is_same(a.options, b.options)) is_same = false;
            }
            if (is_same)
                throw Error("accel '" + a.label + "' and '" + b.label +
                            "' build the same structure: their settings are equal (a "
                            "setting at its default changes nothing), so comparing them shows "
                            "one structure twice; drop one or give it other settings");
        }
}

void check_build_options_used(std::span<const std::string> specs, const AccelOptions& options) {
    std::string chosen;
    bool uses_object_bvhs = false, uses_rebraid_settings = false;
    for (const std::string& spec : specs) {
        const AccelEntry& entry = find_entry(base_name(spec));
        uses_object_bvhs = uses_object_bvhs || entry.has_object_bvhs;
        uses_rebraid_settings = uses_rebraid_settings || entry.has_rebraid_settings;
        chosen += (chosen.empty() ? "" : ",") + spec;
    }
    const auto unused = [&](const std::string& option, bool AccelEntry::*uses) {
        return Error(option + " applies only to " + names_of_structures_using(uses) +
                     ", which --accel " + chosen + " does not build");
    };
    if (options.is_object_builder_given && !uses_object_bvhs)
        throw unused("--object-builder", &AccelEntry::has_object_bvhs);
    if (!options.rebraid_options_given.empty() && !uses_rebraid_settings)
        throw unused(options.rebraid_options_given.front(), &AccelEntry::has_rebraid_settings);
}

std::unique_ptr<Accel> build_accel(std::string_view spec, const Scene& scene,
                                   const AccelOptions& options) {
    options.rebraid.validate();
    const AccelVariant variant = parse_accel_variant(spec, options);
    return variant.entry->build(scene, variant.options);
}

}  // namespace rebraid::cli
