// Options shared by several subcommands.
#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <vector>

#include "accel_factory.h"
#include "commands.h"

namespace rebraid::cli {

void add_common_options(CLI::App& command, CommonOptions& common) {
    command.add_option("--threads", common.threads, "worker threads (0 = all cores)")
        ->check(CLI::Range(0, 4096))
        ->capture_default_str();
}

void add_accel_option(CLI::App& command, std::string& accel_name) {
    accel_name = std::string(kDefaultAccelName);
    command
        .add_option("--accel", accel_name,
                    "acceleration structure: " + accel_names_joined() + " (default " +
                        std::string(kDefaultAccelName) + ")")
        ->type_name("NAME");
}

void add_accel_build_options(CLI::App& command, AccelOptions& options) {
    std::vector<std::string> names;
    for (ObjectBuilderKind kind : object_builder_kinds())
        names.emplace_back(object_builder_name(kind));
    std::string joined;
    for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
    command
        .add_option_function<std::string>(
            "--object-builder",
            [&options](const std::string& name) {
                for (ObjectBuilderKind kind : object_builder_kinds())
                    if (object_builder_name(kind) == name) options.object_builder = kind;
            },
            "object BVHs of twolevel and rebraid: " + joined + " (default " +
                std::string(object_builder_name(options.object_builder)) +
                "); embree-high is rtcBuildBVH with spatial splits, so a triangle may sit in "
                "several leaves")
        ->check(CLI::IsMember(names))
        ->type_name("NAME");
    command
        .add_option("--open-threshold", options.rebraid.open_threshold,
                    "rebraid: open a BRef whose extent along its segment's largest axis exceeds "
                    "this fraction of the segment's (paper 4.2)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str()
        ->type_name("X");
    command
        .add_option("--budget-factor", options.rebraid.budget_factor,
                    "rebraid: extra BRefs per instance (paper 5.2; 0 = the plain two-level top)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str()
        ->type_name("B");
    const std::map<std::string, BudgetRule> budget_rules{
        {"instances", BudgetRule::per_instance}, {"primitives", BudgetRule::per_primitive}};
    command
        .add_option("--budget-rule", options.rebraid.budget_rule,
                    "rebraid: size the BRef budget by instances (--budget-factor x instances, "
                    "the paper's rule for instanced scenes) or primitives (instanced "
                    "primitives / --primitives-per-bref, its rule for objects in world space; "
                    "paper 5.2)")
        ->transform(CLI::CheckedTransformer(budget_rules, CLI::ignore_case))
        ->default_str("instances")
        ->type_name("RULE");
    command
        .add_option("--primitives-per-bref", options.rebraid.primitives_per_bref,
                    "rebraid: primitives per extra BRef under --budget-rule primitives")
        ->check(CLI::PositiveNumber)
        ->capture_default_str()
        ->type_name("P");
    const std::map<std::string, BRefBoundsRule> bounds_rules{
        {"box", BRefBoundsRule::transformed_box},
        {"children", BRefBoundsRule::transformed_children}};
    command
        .add_option("--bref-bounds", options.rebraid.bounds_rule,
                    "rebraid: world boxes of instanced BRefs: box (the node's box transformed, "
                    "paper 5.4) or children (union of its transformed children: tighter)")
        ->transform(CLI::CheckedTransformer(bounds_rules, CLI::ignore_case))
        ->default_str(options.rebraid.bounds_rule == BRefBoundsRule::transformed_box ? "box"
                                                                                     : "children")
        ->type_name("RULE");
}

}  // namespace rebraid::cli
