#include "output_file.h"

#include <filesystem>
#include <fstream>
#include <iostream>

#include "rebraid/core/error.h"

namespace rebraid::cli {

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
    std::ofstream file(path, std::ios::binary);
    if (!file) throw Error("cannot create output file '" + path + "'");
    write(file);
    file.close();
    if (!file) throw Error("cannot write output file '" + path + "'");
}

}  // namespace rebraid::cli
