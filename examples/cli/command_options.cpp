// Options shared by several subcommands.
#include <CLI/CLI.hpp>
#include <string>

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

}  // namespace rebraid::cli
