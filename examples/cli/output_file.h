#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace rebraid::cli {

/// Runs `write` on standard output when `path` is empty, else on the file at `path`, creating
/// its parent directories first. Throws rebraid::Error naming the file and the reason when it
/// cannot be created or written.
void write_output(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Creates the parent directories of `path` when they are missing (nothing for a bare name).
/// Throws rebraid::Error naming the directory and the reason when that fails.
void create_parent_directories(const std::string& path);

/// Checks, before any long work, that the file `path` (called `what` in messages, e.g.
/// "output image") can be written: creates its parent directories, then fails when `path` is a
/// directory or the file cannot be opened for writing, naming the reason. An existing file is
/// left as it is; a new one is removed again. Nothing for an empty path (standard output).
void check_output_file(const std::string& path, const std::string& what);

/// Checks that the file `path` (called `what` in messages, e.g. "ray file") exists, is not a
/// directory and can be read; throws rebraid::Error naming the reason otherwise.
void check_input_file(const std::string& path, const std::string& what);

/// Prints `line` (e.g. "wrote 10000 rays to out/rays.txt") on standard error when that is a
/// terminal, so a person sees what happened; pipes and logs stay clean.
void print_summary_on_terminal(const std::string& line);

}  // namespace rebraid::cli
