#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace rebraid::cli {

/// Runs `write` on standard output when `path` is empty, else on the file at `path`, creating
/// its parent directories first. Throws rebraid::Error naming the file when it cannot be
/// created or written.
void write_output(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Creates the parent directories of `path` when they are missing (nothing for a bare name).
/// Throws rebraid::Error naming the directory when that fails.
void create_parent_directories(const std::string& path);

}  // namespace rebraid::cli
