#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/scene.h"
#include "rebraid/rebraiding/rebraid_settings.h"

namespace rebraid::cli {

/// The structure every command builds when `--accel` is not given.
inline constexpr std::string_view kDefaultAccelName = "rebraid";

/// Which builder makes the object BVHs of the project's two-level structures
/// (`--object-builder`).
enum class ObjectBuilderKind {
    own,            ///< the project's parallel binned-SAH builder
    embree_high,    ///< rtcBuildBVH at high quality with spatial splits
    embree_medium,  ///< rtcBuildBVH at medium quality (binned SAH)
};

/// Everything the command line can tell the structures' builders. A structure builds with what
/// concerns it (the Embree references and `flat` with none of it); check_build_options_used()
/// rejects options the user gave that none of the chosen structures uses.
struct AccelOptions {
    /// Object BVHs of `twolevel` and `rebraid`.
    ObjectBuilderKind object_builder = ObjectBuilderKind::own;
    /// The re-braiding top-level build (`rebraid` only).
    RebraidSettings rebraid;
    /// The re-braiding options the command line gave (e.g. "--opening"), in the order given.
    std::vector<std::string> rebraid_options_given;
    /// Whether the command line gave --object-builder.
    bool is_object_builder_given = false;
    /// Robust mode (`flat:robust=1`, `embree-flat:robust=1`): RTC_SCENE_FLAG_ROBUST on the
    /// Embree structures (Embree's robust traversal and triangle test), the watertight
    /// triangle test (TriangleTest::watertight) on the project's. Off by default, as in an
    /// Embree application that sets no scene flags: the benchmarks compare with Embree as it
    /// runs by default, and the project's structures then run the Möller test as Embree does.
    bool is_robust = false;
    /// Room for spatial splits in the project's own triangle BVHs (`flat`, and the object
    /// BVHs of `twolevel` and `rebraid` from the own builder), as a fraction of the triangles
    /// (BuildSettings::spatial_split_budget; `flat:spatial-splits=0` turns them off).
    float spatial_split_budget = kStaticSpatialSplitBudget;
};

/// The `--opening` name of `rule` ("extent", "sah", "overlap").
std::string_view opening_rule_name(OpeningRule rule);

/// Every OpeningRule, in the order `--help` lists them.
std::span<const OpeningRule> opening_rules();

/// The `--bref-bounds` name of `rule` ("box", "children", "vertices").
std::string_view bref_bounds_rule_name(BRefBoundsRule rule);

/// Every BRefBoundsRule, in the order `--help` lists them.
std::span<const BRefBoundsRule> bref_bounds_rules();

/// The `--object-builder` name of `kind` ("own", "embree-high", "embree-medium").
std::string_view object_builder_name(ObjectBuilderKind kind);

/// Every ObjectBuilderKind, in the order `--help` lists them.
std::span<const ObjectBuilderKind> object_builder_kinds();

/// The ObjectBvhBuilder `kind` stands for; the own builder with `own_settings`.
ObjectBvhBuilder make_object_builder(
    ObjectBuilderKind kind, const BuildSettings& own_settings = static_object_build_settings());

/// One structure the command line can build: its `--accel` name and how to build it.
struct AccelEntry {
    std::string_view name;
    std::string_view description;  ///< one line for `--help`
    std::unique_ptr<Accel> (*build)(const Scene& scene, const AccelOptions& options);
    /// True when AccelOptions::object_builder changes the structure.
    bool has_object_bvhs = false;
    /// True when AccelOptions::rebraid changes the structure.
    bool has_rebraid_settings = false;
    /// True when AccelOptions::is_robust changes the structure.
    bool has_robust_mode = false;
    /// True when AccelOptions::spatial_split_budget changes the structure (its triangle BVHs
    /// come from the own builder).
    bool has_own_triangle_bvhs = false;
};

/// Every structure `--accel` accepts, in the order `--help` lists them.
std::span<const AccelEntry> accel_entries();

/// The valid `--accel` names, in table order.
std::vector<std::string> accel_names();

/// The valid names joined with ", " (for help texts and error messages).
std::string accel_names_joined();

/// A structure with settings of its own: `--accel` accepts `NAME[:KEY=VALUE]...`, so that one
/// run can compare variants, e.g. `rebraid:opening=sah:bref-bounds=children`. Keys are the
/// build options' long names without dashes in front (accel_variant_keys()); each overrides the
/// command line's value for this structure only.
struct AccelVariant {
    const AccelEntry* entry = nullptr;
    AccelOptions options;
    std::string label;  ///< the whole `NAME[:KEY=VALUE]...` text, naming it in outputs
};

/// The keys a variant suffix accepts, joined with ", " (for help texts and error messages).
std::string accel_variant_keys();

/// Parses `spec` (`NAME[:KEY=VALUE]...`) on top of `base`; throws rebraid::Error naming the
/// spec and the bad name, key or value. The settings are validated.
AccelVariant parse_accel_variant(std::string_view spec, const AccelOptions& base = {});

/// The entry of the structure `spec` names (a variant suffix is parsed and checked too);
/// throws rebraid::Error listing the valid names when there is none. Commands call this
/// before loading a scene, so a typo fails fast.
const AccelEntry& find_accel(std::string_view spec);

/// Throws rebraid::Error when two of `variants` build the same structure: the same name and
/// the same settings, such as `rebraid` and `rebraid:opening=sah` while sah is the default. A
/// comparison would show one structure twice and suggest a difference that is not there.
void check_variants_differ(std::span<const AccelVariant> variants);

/// Throws rebraid::Error when the command line gave a build option (`--opening`,
/// `--object-builder`, ...) that none of the structures `specs` names uses, since it would
/// change nothing.
void check_build_options_used(std::span<const std::string> specs, const AccelOptions& options);

/// Builds the structure `spec` names over `scene` with `options`, overridden by the spec's
/// variant suffix (validated first). The scene must outlive the result.
std::unique_ptr<Accel> build_accel(std::string_view spec, const Scene& scene,
                                   const AccelOptions& options = {});

}  // namespace rebraid::cli
