#include "output_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "rebraid/core/error.h"

namespace rebraid::cli {

namespace {

/// The reason the last failed file operation gives, e.g. "Permission denied".
std::string last_reason() {
    return errno != 0 ? std::strerror(errno) : "unknown reason";
}

}  // namespace

void create_parent_directories(const std::string& path) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (parent.empty()) return;
    std::error_code error;
    std::filesystem::create_directories(parent, error);
    if (error) throw Error("cannot create directory '" + parent.string() + "': " + error.message());
}

void write_output(const std::string& path, const std::function<void(std::ostream&)>& write) {
    if (path.empty()) {
        write(std::cout);
        std::cout.flush();
        if (!std::cout) throw Error("cannot write to standard output");
        return;
    }
    create_parent_directories(path);
    errno = 0;
    std::ofstream file(path, std::ios::binary);
    if (!file) throw Error("cannot create output file '" + path + "': " + last_reason());
    write(file);
    file.close();
    if (!file) throw Error("cannot write output file '" + path + "': " + last_reason());
}

void check_output_file(const std::string& path, const std::string& what) {
    if (path.empty()) return;
    create_parent_directories(path);
    std::error_code error;
    if (std::filesystem::is_directory(path, error))
        throw Error(what + " '" + path + "' is a directory; give a file name");
    const bool existed = std::filesystem::exists(path, error);
    errno = 0;
    // Opened for appending, so an existing file keeps its contents until the real write.
    std::ofstream probe(path, std::ios::binary | std::ios::app);
    if (!probe) throw Error("cannot write " + what + " '" + path + "': " + last_reason());
    probe.close();
    if (!existed) std::filesystem::remove(path, error);
}

void check_input_file(const std::string& path, const std::string& what) {
    std::error_code error;
    if (!std::filesystem::exists(path, error)) throw Error(what + " '" + path + "' does not exist");
    if (std::filesystem::is_directory(path, error))
        throw Error(what + " '" + path + "' is a directory, not a file");
    errno = 0;
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw Error("cannot read " + what + " '" + path + "': " + last_reason());
}

void print_summary_on_terminal(const std::string& line) {
    if (::isatty(STDERR_FILENO)) std::cerr << line << "\n";
}

}  // namespace rebraid::cli
