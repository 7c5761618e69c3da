#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rebraid::cli {

/// What one method measured on one frame of `rebraid animate`.
struct AnimateFrameRow {
    int frame = 0;
    float time = 0.0f;          ///< seconds of animation
    double animation_ms = 0.0;  ///< posing the dynamic part (shared by every method)
    double update_ms = 0.0;     ///< object BVHs / geometries brought up to date
    double top_ms = 0.0;        ///< top level rebuilt / scene committed
    double render_ms = 0.0;     ///< primary plus diffuse rays traced (closest hit)
    std::optional<double> sah;  ///< none for Embree's structures
    double frame_ms() const { return animation_ms + update_ms + top_ms + render_ms; }
};

/// One method's rows over the run.
struct AnimateMethodResult {
    std::string method;  ///< "embree-flat", "rebraid+rotate", ...
    double build_ms = 0.0;
    std::vector<AnimateFrameRow> frames;
};

/// CSV: a header, then one row per frame and method (frame-major).
void write_animate_csv(std::ostream& out, const std::vector<AnimateMethodResult>& results);

/// The JSON summary: one object per method (method, mean_frame_ms, max_frame_ms,
/// mean_animation_ms, mean_update_ms, mean_top_ms, mean_render_ms, final_sah, ...).
nlohmann::ordered_json animate_summary_json(const std::vector<AnimateMethodResult>& results);

/// The summary as a table for people.
void print_animate_table(std::ostream& out, const std::vector<AnimateMethodResult>& results);

/// Throws rebraid::Error saying what to install when /usr/bin/python3, its matplotlib or
/// bench/plot_animate.py is missing; `animate --plot` calls it before the first frame.
void check_plot_tools();

/// Plots frame times from the CSV at `csv_path` into `png_path` with bench/plot_animate.py
/// and /usr/bin/python3. Throws rebraid::Error when the script, python or matplotlib is
/// missing or the script fails.
void plot_animate_csv(const std::string& csv_path, const std::string& png_path);

}  // namespace rebraid::cli
