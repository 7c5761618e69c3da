#pragma once

#include <functional>
#include <string>

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace rebraid::cli {

struct AccelOptions;           // accel_factory.h
enum class ObjectBuilderKind;  // accel_factory.h

/// Options every subcommand accepts.
struct CommonOptions {
    /// Worker threads for TBB; 0 = as many as the machine has.
    int threads = 0;
};

/// The work of the subcommand the user chose. Subcommands only record it while parsing;
/// main runs it afterwards, once the thread limit is in place.
using CommandAction = std::function<void()>;

/// Adds `--threads` to `command`, bound to `common`.
void add_common_options(CLI::App& command, CommonOptions& common);

/// Adds `--accel NAME` to `command`, bound to `accel_name` (help lists the valid names).
void add_accel_option(CLI::App& command, std::string& accel_name);

/// Adds `--object-builder` and the re-braiding options (`--open-threshold`, `--opening`, ...),
/// bound to `options`, which also records which of them the user gave.
void add_accel_build_options(CLI::App& command, AccelOptions& options);

/// Adds `option` (e.g. "--object-builder") choosing an object-BVH builder by name into
/// `target`, its help text `what` followed by the names and the default.
CLI::Option* add_object_builder_option(CLI::App& command, const std::string& option,
                                       ObjectBuilderKind& target, const std::string& what);

/// Each registers one subcommand on `app`; when it is chosen, `action` is set to its work.
void add_trace_command(CLI::App& app, CommonOptions& common, CommandAction& action);
void add_stats_command(CLI::App& app, CommonOptions& common, CommandAction& action);
void add_render_command(CLI::App& app, CommonOptions& common, CommandAction& action);
void add_rays_command(CLI::App& app, CommonOptions& common, CommandAction& action);
void add_bench_command(CLI::App& app, CommonOptions& common, CommandAction& action);
void add_generate_command(CLI::App& app, CommonOptions& common, CommandAction& action);
void add_animate_command(CLI::App& app, CommonOptions& common, CommandAction& action);
void add_export_command(CLI::App& app, CommonOptions& common, CommandAction& action);

}  // namespace rebraid::cli
