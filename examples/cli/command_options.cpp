// Options shared by several subcommands.
#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <vector>

#include "accel_factory.h"
#include "commands.h"
#include "option_checks.h"

namespace rebraid::cli {

void add_common_options(CLI::App& command, CommonOptions& common) {
    command.add_option("--threads", common.threads, "worker threads (0 = all cores)")
        ->check(whole_number(0, 4096))
        ->capture_default_str()
        ->type_name("N");
}

void add_accel_option(CLI::App& command, std::string& accel_name) {
    accel_name = std::string(kDefaultAccelName);
    command
        .add_option("--accel", accel_name,
                    "acceleration structure: " + accel_names_joined() + " (default " +
                        std::string(kDefaultAccelName) +
                        "); NAME:KEY=VALUE[:KEY=VALUE...] overrides build options for it, "
                        "keys: " +
                        accel_variant_keys())
        ->type_name("NAME");
}

CLI::Option* add_object_builder_option(CLI::App& command, const std::string& option,
                                       ObjectBuilderKind& target, const std::string& what) {
    std::vector<std::string> names;
    for (ObjectBuilderKind kind : object_builder_kinds())
        names.emplace_back(object_builder_name(kind));
    const std::string joined = join_names(names);
    return command
        .add_option_function<std::string>(
            option,
            [&target](const std::string& name) {
                for (ObjectBuilderKind kind : object_builder_kinds())
                    if (object_builder_name(kind) == name) target = kind;
            },
            what + ": " + joined + " (default " + std::string(object_builder_name(target)) +
                "); embree-high is rtcBuildBVH with spatial splits, so a triangle may sit in "
                "several leaves")
        ->check(one_of(names))
        ->type_name("NAME");
}

void add_accel_build_options(CLI::App& command, AccelOptions& options) {
    add_object_builder_option(command, "--object-builder", options.object_builder,
                              "object BVHs of twolevel and rebraid");
    command
        .add_option("--open-threshold", options.rebraid.open_threshold,
                    "rebraid: open a BRef whose extent along its segment's largest axis exceeds "
                    "this fraction of the segment's (paper 4.2)")
        ->check(number_at_least(0))
        ->capture_default_str()
        ->type_name("X");
    command
        .add_option(
            "--budget-factor", options.rebraid.budget_factor,
            "rebraid: extra BRefs per instance (paper 5.2; 0 with --budget-rule instances = "
            "the plain two-level top)")
        ->check(number_between(0, 1e6))
        ->capture_default_str()
        ->type_name("B");
    const std::map<std::string, BudgetRule> budget_rules{{"instances", BudgetRule::per_instance},
                                                         {"primitives", BudgetRule::per_primitive},
                                                         {"larger", BudgetRule::larger}};
    command
        .add_option("--budget-rule", options.rebraid.budget_rule,
                    "rebraid: size the BRef budget by instances (--budget-factor x instances, "
                    "the paper's rule for instanced scenes), primitives (instanced "
                    "primitives / --primitives-per-bref, its rule for objects in world space; "
                    "paper 5.2) or the larger of the two")
        ->transform(named_value(budget_rules))
        ->default_str("larger")
        ->type_name("RULE");
    command
        .add_option("--primitives-per-bref", options.rebraid.primitives_per_bref,
                    "rebraid: primitives per extra BRef under --budget-rule primitives")
        ->check(number_at_least(1))
        ->capture_default_str()
        ->type_name("P");
    std::map<std::string, BRefBoundsRule> bounds_rules;
    for (BRefBoundsRule rule : bref_bounds_rules())
        bounds_rules.emplace(std::string(bref_bounds_rule_name(rule)), rule);
    command
        .add_option("--bref-bounds", options.rebraid.bounds_rule,
                    "rebraid: world boxes of instanced BRefs: box (the node's box transformed, "
                    "paper 5.4), children (union of its transformed children: tighter) or "
                    "vertices (box of its transformed vertices: tight)")
        ->transform(named_value(bounds_rules))
        ->default_str(std::string(bref_bounds_rule_name(options.rebraid.bounds_rule)))
        ->type_name("RULE");
    std::map<std::string, OpeningRule> opening_names;
    for (OpeningRule rule : opening_rules())
        opening_names.emplace(std::string(opening_rule_name(rule)), rule);
    command
        .add_option("--opening", options.rebraid.opening_rule,
                    "rebraid: which BRefs open: extent (the paper's rule, 4.2), sah (the "
                    "paper's candidates, opened only where the estimated SAH falls, with real "
                    "child primitive counts) or overlap (candidates overlapping other "
                    "instances' BRefs by --overlap-threshold, then the SAH test)")
        ->transform(named_value(opening_names))
        ->default_str(std::string(opening_rule_name(options.rebraid.opening_rule)))
        ->type_name("RULE");
    command.add_flag("--open-leaves", options.rebraid.open_leaves,
                     "rebraid: also open BRefs to object leaves of several triangles into one "
                     "BRef per triangle");
    command
        .add_option("--instance-entry-cost", options.rebraid.instance_entry_cost,
                    "rebraid, --opening sah|overlap: SAH cost of one more instance entry (ray "
                    "transform) per unit of BRef area, relative to a node visit")
        ->check(number_at_least(0))
        ->capture_default_str()
        ->type_name("C");
    command
        .add_option("--estimate-levels", options.rebraid.estimate_levels,
                    "rebraid, --opening sah|overlap: wide top-level levels the SAH estimate "
                    "builds before assuming lower nodes as large as their parent")
        ->check(whole_number(0, 8))
        ->capture_default_str()
        ->type_name("L");
    command
        .add_option("--budget-doublings", options.rebraid.budget_doublings,
                    "rebraid: when the build spent its budget, build again with it doubled, "
                    "and when that lowers the exact SAH cost by 1 % of the top level's own, "
                    "with it doubled this many times; keep the cheapest build (0: build once)")
        ->check(whole_number(0, 16))
        ->capture_default_str()
        ->type_name("D");
    command
        .add_option("--overlap-threshold", options.rebraid.overlap_threshold,
                    "rebraid, --opening overlap: least fraction of a BRef's box shared with "
                    "other instances' BRefs for it to be a candidate")
        ->check(number_at_least(0))
        ->capture_default_str()
        ->type_name("F");
    // Which options the user gave, so a command can reject those none of its structures uses.
    command.parse_complete_callback([&command, &options] {
        options.is_object_builder_given = command.count("--object-builder") > 0;
        for (const char* name :
             {"--open-threshold", "--budget-factor", "--budget-rule", "--primitives-per-bref",
              "--bref-bounds", "--opening", "--open-leaves", "--instance-entry-cost",
              "--estimate-levels", "--budget-doublings", "--overlap-threshold"})
            if (command.count(name) > 0) options.rebraid_options_given.emplace_back(name);
    });
}

}  // namespace rebraid::cli
