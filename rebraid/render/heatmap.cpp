#include "rebraid/render/heatmap.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "rebraid/core/error.h"
#include "rebraid/render/bitmap_font.h"
#include "rebraid/render/colour.h"
#include "rebraid/render/image_draw.h"

namespace rebraid::viewer {

namespace {

std::string format(const char* pattern, double value) {
    char text[64];
    std::snprintf(text, sizeof text, pattern, value);
    return text;
}

double per_ray(std::uint64_t total, std::uint64_t ray_count) {
    return ray_count == 0 ? 0.0 : static_cast<double>(total) / static_cast<double>(ray_count);
}

/// Seconds for one parallel pass of plain closest-hit queries over the panel's rays.
double time_primary_pass(const Accel& accel, const Camera& camera, int width, int height) {
    const auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        std::uint32_t hit_count = 0;
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < width; ++x)
                hit_count +=
                    accel
                        .intersect(camera.ray_through(static_cast<float>(x) + 0.5f,
                                                      static_cast<float>(y) + 0.5f, width, height))
                        .is_hit();
        // Keeps the queries observable; the count itself is not needed.
        static_cast<void>(hit_count);
    });
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The value `percentile` percent of all panels' pixels stay at or below, at least 1.
double shared_scale(std::span<const HeatmapPanel> panels, const HeatmapSettings& settings) {
    std::vector<std::uint64_t> values;
    for (const HeatmapPanel& panel : panels)
        for (std::size_t p = 0; p < panel.per_pixel.size(); ++p)
            values.push_back(panel.value(p, settings.metric));
    if (values.empty()) return 1.0;
    const auto rank = static_cast<std::size_t>(
        std::ceil(settings.scale_percentile / 100.0 * static_cast<double>(values.size())));
    const std::size_t at = std::min(values.size() - 1, rank == 0 ? 0 : rank - 1);
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(at),
                     values.end());
    return std::max<double>(1.0, static_cast<double>(values[at]));
}

std::string metric_caption(HeatMetric metric) {
    switch (metric) {
        case HeatMetric::nodes:
            return "nodes visited per ray";
        case HeatMetric::triangles:
            return "triangles tested per ray";
        case HeatMetric::total:
            break;
    }
    return "nodes + triangles per ray";
}

/// A colour bar with its scale under it, in the bottom-left corner of `image`.
void draw_legend(Image& image, HeatMetric metric, double scale_max, bool is_clipped, int s) {
    const int margin = 4 * s, pad = 3 * s;
    const std::string caption = metric_caption(metric);
    const int bar_width = std::max(text_width(caption, s), 120 * s);
    const int bar_height = 6 * s;
    const int box_height =
        pad + kGlyphHeight * s + 2 * s + bar_height + 2 * s + kGlyphHeight * s + pad;
    const PixelRect box{margin, image.height - margin - box_height, bar_width + 2 * pad,
                        box_height};
    fill_rect(image, box, {0.0f, 0.0f, 0.0f}, 0.6f);
    const Vec3f white{1.0f, 1.0f, 1.0f};
    int y = box.y + pad;
    draw_text(image, box.x + pad, y, caption, s, white);
    y += kGlyphHeight * s + 2 * s;
    for (int i = 0; i < bar_width; ++i)
        fill_rect(image, {box.x + pad + i, y, 1, bar_height},
                  heat_colour(static_cast<float>(i) / static_cast<float>(bar_width - 1)));
    y += bar_height + 2 * s;
    const std::string low = "0";
    const std::string middle = format("%.0f", scale_max / 2.0);
    const std::string high = format("%.0f", scale_max) + (is_clipped ? "+" : "");
    draw_text(image, box.x + pad, y, low, s, white);
    draw_text(image, box.x + pad + (bar_width - text_width(middle, s)) / 2, y, middle, s, white);
    draw_text(image, box.x + pad + bar_width - text_width(high, s), y, high, s, white);
}

/// Whether the panel's structure counted its work: Embree's traversal counts nothing, and
/// every ray of a counting structure visits at least its root.
bool has_counts(const HeatmapPanel& panel) {
    return panel.ray_count == 0 || panel.totals.nodes_visited + panel.totals.triangles_tested > 0;
}

}  // namespace

std::string_view heat_metric_name(HeatMetric metric) {
    switch (metric) {
        case HeatMetric::total:
            return "total";
        case HeatMetric::nodes:
            return "nodes";
        case HeatMetric::triangles:
            return "triangles";
    }
    return "unknown";
}

void HeatmapSettings::validate() const {
    auto fail = [](const std::string& what) { throw Error("HeatmapSettings: " + what); };
    if (width < 1 || width > 32768)
        fail("width " + std::to_string(width) + " is outside [1, 32768]");
    if (height < 1 || height > 32768)
        fail("height " + std::to_string(height) + " is outside [1, 32768]");
    if (timing_run_count < 0)
        fail("timing_run_count " + std::to_string(timing_run_count) + " is negative");
    if (!(scale_percentile > 0.0f && scale_percentile <= 100.0f))
        fail("scale_percentile " + std::to_string(scale_percentile) + " is outside (0, 100]");
}

std::uint64_t HeatmapPanel::value(std::size_t pixel, HeatMetric metric) const {
    const TraversalCounters& counters = per_pixel[pixel];
    switch (metric) {
        case HeatMetric::nodes:
            return counters.nodes_visited;
        case HeatMetric::triangles:
            return counters.triangles_tested;
        case HeatMetric::total:
            break;
    }
    return counters.nodes_visited + counters.triangles_tested;
}

HeatmapPanel trace_heatmap(std::string label, const Accel& accel, const Camera& camera,
                           const HeatmapSettings& settings, const RenderControl& control) {
    settings.validate();
    HeatmapPanel panel;
    panel.label = std::move(label);
    panel.width = settings.width;
    panel.height = settings.height;
    panel.per_pixel.assign(static_cast<std::size_t>(settings.width) * settings.height, {});
    std::vector<char> row_is_done;
    panel.rows_done = for_each_row(
        settings.height, control,
        [&](int y) {
            for (int x = 0; x < settings.width; ++x) {
                const Ray ray =
                    camera.ray_through(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f,
                                       settings.width, settings.height);
                accel.intersect_counted(
                    ray, &panel.per_pixel[static_cast<std::size_t>(y) * settings.width + x]);
            }
        },
        row_is_done);
    for (const TraversalCounters& counters : panel.per_pixel) {
        panel.totals.nodes_visited += counters.nodes_visited;
        panel.totals.triangles_tested += counters.triangles_tested;
    }
    panel.ray_count = static_cast<std::uint64_t>(panel.rows_done) * settings.width;

    const bool is_stopped =
        control.stop_requested && control.stop_requested->load(std::memory_order_relaxed);
    if (panel.rows_done == settings.height && !is_stopped && settings.timing_run_count > 0) {
        std::vector<double> seconds;
        for (int run = 0; run < settings.timing_run_count; ++run)
            seconds.push_back(time_primary_pass(accel, camera, settings.width, settings.height));
        std::ranges::sort(seconds);
        const double median = seconds[seconds.size() / 2];
        if (median > 0.0)
            panel.mrays_per_second = static_cast<double>(panel.ray_count) / median / 1e6;
    }
    return panel;
}

Image draw_heatmaps(std::span<const HeatmapPanel> panels, const HeatmapSettings& settings) {
    if (panels.empty()) throw Error("draw_heatmaps: no panels");
    const int width = panels[0].width, height = panels[0].height;
    for (const HeatmapPanel& panel : panels)
        if (panel.width != width || panel.height != height)
            throw Error("draw_heatmaps: panel '" + panel.label + "' is " +
                        std::to_string(panel.width) + " x " + std::to_string(panel.height) +
                        ", the first is " + std::to_string(width) + " x " + std::to_string(height));
    const double scale_max = shared_scale(panels, settings);
    bool is_clipped = false;
    const int panel_count = static_cast<int>(panels.size());
    Image image = Image::filled(width * panel_count, height);
    for (int i = 0; i < panel_count; ++i)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const std::uint64_t value = panels[static_cast<std::size_t>(i)].value(
                    static_cast<std::size_t>(y) * width + x, settings.metric);
                is_clipped = is_clipped || static_cast<double>(value) > scale_max;
                const float fraction = static_cast<float>(static_cast<double>(value) / scale_max);
                image.set_pixel(i * width + x, y, srgb_to_linear(heat_colour(fraction)));
            }

    // Text grows with the panel so it stays readable on large images.
    const int s = std::clamp(width / 240, 1, 4);
    for (int i = 0; i < panel_count; ++i) {
        const HeatmapPanel& panel = panels[static_cast<std::size_t>(i)];
        const int x = i * width + 4 * s;
        if (i > 0) fill_rect(image, {i * width, 0, s, height}, {0.9f, 0.9f, 0.9f});
        std::string title = panel.label;
        if (panel.mrays_per_second > 0.0)
            title += "  " + format("%.1f", panel.mrays_per_second) + " Mrays/s";
        const PixelRect title_box = draw_label(image, x, 4 * s, title, s);
        const std::string work =
            !has_counts(panel)
                ? std::string("work not counted")
                : format("%.1f", per_ray(panel.totals.nodes_visited, panel.ray_count)) +
                      " nodes  " +
                      format("%.1f", per_ray(panel.totals.triangles_tested, panel.ray_count)) +
                      " tris per ray";
        draw_label(image, x, title_box.y + title_box.height + s, work, s);
    }
    draw_legend(image, settings.metric, scale_max, is_clipped, s);
    return image;
}

std::string describe_heatmap_totals(const HeatmapPanel& panel) {
    if (!has_counts(panel)) {
        std::string text = panel.label +
                           ": work not counted (the structure's traversal, such as "
                           "Embree's, does not report it)";
        if (panel.mrays_per_second > 0.0)
            text += ", " + format("%.2f", panel.mrays_per_second) + " Mrays/s";
        return text;
    }
    std::string text =
        panel.label + ": " + std::to_string(panel.totals.nodes_visited) + " nodes visited, " +
        std::to_string(panel.totals.triangles_tested) + " triangles tested by " +
        std::to_string(panel.ray_count) + " primary rays (" +
        format("%.2f", per_ray(panel.totals.nodes_visited, panel.ray_count)) + " nodes, " +
        format("%.2f", per_ray(panel.totals.triangles_tested, panel.ray_count)) +
        " triangles per ray)";
    if (panel.mrays_per_second > 0.0)
        text += ", " + format("%.2f", panel.mrays_per_second) + " Mrays/s";
    return text;
}

}  // namespace rebraid::viewer
