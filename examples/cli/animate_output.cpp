#include "animate_output.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "rebraid/core/error.h"

namespace rebraid::cli {

namespace {

/// The Python that plots: Debian's, which python3-matplotlib installs into.
constexpr const char* kPython = "/usr/bin/python3";

struct MethodSummary {
    double mean_frame = 0, max_frame = 0, mean_animation = 0, mean_update = 0, mean_top = 0,
           mean_render = 0;
    std::optional<double> final_sah;
};

MethodSummary summarize(const AnimateMethodResult& result) {
    MethodSummary summary;
    if (result.frames.empty()) return summary;
    for (const AnimateFrameRow& row : result.frames) {
        summary.mean_frame += row.frame_ms();
        summary.max_frame = std::max(summary.max_frame, row.frame_ms());
        summary.mean_animation += row.animation_ms;
        summary.mean_update += row.update_ms;
        summary.mean_top += row.top_ms;
        summary.mean_render += row.render_ms;
    }
    const auto count = static_cast<double>(result.frames.size());
    summary.mean_frame /= count;
    summary.mean_animation /= count;
    summary.mean_update /= count;
    summary.mean_top /= count;
    summary.mean_render /= count;
    summary.final_sah = result.frames.back().sah;
    return summary;
}

std::string shell_quote(const std::string& text) {
    std::string quoted = "'";
    for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

/// bench/plot_animate.py: beside the working directory, or in the source tree the binary
/// was built from (its CMakeCache.txt names it).
std::filesystem::path find_plot_script() {
    const std::filesystem::path relative = "bench/plot_animate.py";
    if (const char* override_path = std::getenv("REBRAID_PLOT_SCRIPT")) return override_path;
    std::error_code error;
    if (std::filesystem::exists(relative, error)) return relative;
    std::filesystem::path dir = std::filesystem::read_symlink("/proc/self/exe", error);
    for (int level = 0; level < 4 && !error && dir.has_parent_path(); ++level) {
        dir = dir.parent_path();
        std::ifstream cache(dir / "CMakeCache.txt");
        for (std::string line; cache && std::getline(cache, line);) {
            const std::string key = "CMAKE_HOME_DIRECTORY:INTERNAL=";
            if (line.rfind(key, 0) == 0)
                return std::filesystem::path(line.substr(key.size())) / relative;
        }
    }
    return relative;
}

}  // namespace

void write_animate_csv(std::ostream& out, const std::vector<AnimateMethodResult>& results) {
    out << "frame,time,method,animation_ms,update_ms,top_ms,render_ms,frame_ms,sah\n";
    const std::size_t frame_count = results.empty() ? 0 : results.front().frames.size();
    for (std::size_t f = 0; f < frame_count; ++f)
        for (const AnimateMethodResult& result : results) {
            const AnimateFrameRow& row = result.frames[f];
            out << row.frame << ',' << row.time << ',' << result.method << ',' << row.animation_ms
                << ',' << row.update_ms << ',' << row.top_ms << ',' << row.render_ms << ','
                << row.frame_ms() << ',';
            if (row.sah) out << *row.sah;
            out << '\n';
        }
}

nlohmann::ordered_json animate_summary_json(const std::vector<AnimateMethodResult>& results) {
    nlohmann::ordered_json all = nlohmann::ordered_json::array();
    for (const AnimateMethodResult& result : results) {
        const MethodSummary summary = summarize(result);
        nlohmann::ordered_json json;
        json["method"] = result.method;
        json["frames"] = result.frames.size();
        json["mean_frame_ms"] = summary.mean_frame;
        json["max_frame_ms"] = summary.max_frame;
        json["mean_animation_ms"] = summary.mean_animation;
        json["mean_update_ms"] = summary.mean_update;
        json["mean_top_ms"] = summary.mean_top;
        json["mean_render_ms"] = summary.mean_render;
        json["final_sah"] = summary.final_sah ? nlohmann::ordered_json(*summary.final_sah)
                                              : nlohmann::ordered_json(nullptr);
        json["build_ms"] = result.build_ms;
        all.push_back(std::move(json));
    }
    return all;
}

void print_animate_table(std::ostream& out, const std::vector<AnimateMethodResult>& results) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-24s %9s %9s %9s %9s %9s %9s %9s\n", "method", "frame_ms",
                  "max_ms", "anim_ms", "update_ms", "top_ms", "render_ms", "final_sah");
    out << line;
    for (const AnimateMethodResult& result : results) {
        const MethodSummary s = summarize(result);
        char sah[32] = "-";
        if (s.final_sah) std::snprintf(sah, sizeof sah, "%.2f", *s.final_sah);
        std::snprintf(line, sizeof line, "  %-24s %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9s\n",
                      result.method.c_str(), s.mean_frame, s.max_frame, s.mean_animation,
                      s.mean_update, s.mean_top, s.mean_render, sah);
        out << line;
    }
}

void check_plot_tools() {
    std::error_code error;
    if (!std::filesystem::exists(kPython, error))
        throw Error("--plot needs " + std::string(kPython) +
                    ", which is missing: install Debian's python3-matplotlib "
                    "(bash scripts/install-deps.sh does), or leave out --plot");
    if (std::system((std::string(kPython) + " -c 'import matplotlib' >/dev/null 2>&1").c_str()) !=
        0)
        throw Error("--plot needs matplotlib for " + std::string(kPython) +
                    ", which is missing: install Debian's python3-matplotlib "
                    "(bash scripts/install-deps.sh does), or leave out --plot");
    const std::filesystem::path script = find_plot_script();
    if (!std::filesystem::exists(script, error))
        throw Error("--plot needs the plot script '" + script.string() +
                    "', which is missing: run from the repository root, or set "
                    "REBRAID_PLOT_SCRIPT to bench/plot_animate.py");
}

void plot_animate_csv(const std::string& csv_path, const std::string& png_path) {
    check_plot_tools();
    const std::string command = std::string(kPython) + " " +
                                shell_quote(find_plot_script().string()) + " " +
                                shell_quote(csv_path) + " " + shell_quote(png_path);
    if (std::system(command.c_str()) != 0) throw Error("--plot: '" + command + "' failed");
}

}  // namespace rebraid::cli
