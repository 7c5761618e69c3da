// The `rebraid` command: one executable, one subcommand per task (see README).
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <optional>
#include <string>

#include "commands.h"
#include "rebraid/core/error.h"

int main(int argc, char** argv) {
    using namespace rebraid::cli;
    std::ios::sync_with_stdio(false);

    CLI::App app{"rebraid: re-braided two-level BVHs for instanced scenes"};
    app.set_version_flag("--version", std::string("rebraid ") + REBRAID_VERSION);
    app.require_subcommand(1);
    // Parse errors read like every other error: "rebraid: --width: 'abc' is not a whole number".
    app.failure_message([](const CLI::App*, const CLI::Error& error) {
        return "rebraid: " + std::string(error.what()) + "\nRun with --help for the options.\n";
    });
    app.footer(
        "A SCENE is a .gltf or .glb file; without one, commands use the built-in "
        "default scene.\nRun 'rebraid COMMAND --help' for a command's options.");

    CommonOptions common;
    CommandAction action;
    add_trace_command(app, common, action);
    add_stats_command(app, common, action);
    add_render_command(app, common, action);
    add_rays_command(app, common, action);
    add_bench_command(app, common, action);
    add_generate_command(app, common, action);
    add_animate_command(app, common, action);
    add_export_command(app, common, action);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // CLI11 prints the message; every error exits with 1, as the README promises
        // (CLI11's own codes would be 105, 106, ...). --help and --version are not errors.
        return app.exit(e) == 0 ? 0 : 1;
    }

    try {
        // Lives for the whole run, so every TBB algorithm the command calls honours it.
        std::optional<tbb::global_control> thread_limit;
        if (common.threads > 0)
            thread_limit.emplace(tbb::global_control::max_allowed_parallelism,
                                 static_cast<std::size_t>(common.threads));
        if (action) action();
    } catch (const rebraid::Error& e) {
        std::cerr << "rebraid: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "rebraid: unexpected error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
