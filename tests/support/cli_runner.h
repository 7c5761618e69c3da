// Running the built `rebraid` binary from end-to-end tests: one scratch folder per test,
// both output streams captured, the exit code decoded.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <span>
#include <sstream>
#include <string>
#include <string_view>

namespace rebraid::test {

/// What a finished command left behind.
struct CommandResult {
    int exit_code = -1;  ///< -1 when the process did not exit normally (a signal: a crash)
    std::string out;     ///< standard output
    std::string err;     ///< standard error
};

inline std::string read_text_file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

inline void write_text_file(const std::filesystem::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    ASSERT_TRUE(out.good()) << path;
}

/// `text` single-quoted for the shell.
inline std::string shell_quote(std::string_view text) {
    std::string quoted = "'";
    for (const char c : text) {
        if (c == '\'')
            quoted += "'\\''";
        else
            quoted += c;
    }
    return quoted + "'";
}

/// A folder of the running test alone, REBRAID_TEST_TMP/group/Suite.Name: ctest runs tests
/// in parallel processes, which must not share output files. Emptied first when `fresh`.
inline std::filesystem::path test_scratch_dir(std::string_view group, bool fresh = false) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::filesystem::path dir = std::filesystem::path(REBRAID_TEST_TMP) / std::string(group) /
                                      (std::string(info->test_suite_name()) + "." + info->name());
    if (fresh) std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// The shell command line that runs the rebraid binary with `arguments`, each quoted.
inline std::string rebraid_command_line(std::span<const std::string> arguments) {
    std::string command = shell_quote(REBRAID_CLI);
    // Appended piecewise: GCC 12 warns (falsely, -Wrestrict) on "literal" + std::string&&.
    for (const std::string& argument : arguments) {
        command += ' ';
        command += shell_quote(argument);
    }
    return command;
}

/// Runs the shell command line `command`, its output streams going to stdout.txt and
/// stderr.txt in `dir`.
inline CommandResult run_shell_in(const std::filesystem::path& dir, const std::string& command) {
    const std::filesystem::path out_path = dir / "stdout.txt", err_path = dir / "stderr.txt";
    std::string redirected = command;
    redirected += " >";
    redirected += shell_quote(out_path.string());
    redirected += " 2>";
    redirected += shell_quote(err_path.string());
    const int status = std::system(redirected.c_str());
    CommandResult result;
    result.exit_code = (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
    result.out = read_text_file(out_path);
    result.err = read_text_file(err_path);
    return result;
}

/// Runs the rebraid binary with `arguments`, its output streams going to stdout.txt and
/// stderr.txt in `dir`. With a timeout, a hang ends as a failure instead of blocking the suite.
inline CommandResult run_rebraid_in(const std::filesystem::path& dir,
                                    std::span<const std::string> arguments,
                                    int timeout_seconds = 0) {
    std::string command;
    if (timeout_seconds > 0) command = "timeout " + std::to_string(timeout_seconds) + " ";
    command += rebraid_command_line(arguments);
    return run_shell_in(dir, command);
}

inline CommandResult run_rebraid_in(const std::filesystem::path& dir,
                                    std::initializer_list<std::string> arguments,
                                    int timeout_seconds = 0) {
    return run_rebraid_in(dir, std::span<const std::string>(arguments.begin(), arguments.size()),
                          timeout_seconds);
}

}  // namespace rebraid::test
