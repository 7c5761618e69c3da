#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rebraid/core/accel.h"
#include "rebraid/render/camera.h"
#include "rebraid/render/image_io.h"
#include "rebraid/render/render_control.h"

namespace rebraid::viewer {

/// Which work a heatmap colours.
enum class HeatMetric {
    total,      ///< nodes visited + triangles tested (the README's SAH cost of the ray)
    nodes,      ///< nodes visited
    triangles,  ///< triangles tested
};

/// The name `--heat` uses ("total", "nodes", "triangles").
std::string_view heat_metric_name(HeatMetric metric);

/// Parameters of the traversal heatmap.
struct HeatmapSettings {
    /// Size of one panel in pixels (one primary ray per pixel centre).
    int width = 640;
    int height = 360;
    HeatMetric metric = HeatMetric::total;
    /// Passes of plain intersect over the primary rays timed for Mrays/s (median reported).
    int timing_run_count = 3;
    /// Pixels above this percentile of all panels' values get the top colour, so a few
    /// extreme rays do not wash out the rest. In (0, 100].
    float scale_percentile = 99.5f;

    /// Throws rebraid::Error naming the first field out of range.
    void validate() const;
};

/// The work each primary ray of one structure did, and how fast it traced them.
struct HeatmapPanel {
    std::string label;  ///< the structure's name, drawn on the panel
    int width = 0;
    int height = 0;
    std::vector<TraversalCounters> per_pixel;  ///< row-major, top row first
    TraversalCounters totals;                  ///< summed in pixel order
    std::uint64_t ray_count = 0;               ///< rays traced (pixels of finished rows)
    double mrays_per_second = 0.0;             ///< closest-hit primary rays, uncounted
    int rows_done = 0;

    /// The metric's value at pixel index `pixel`.
    std::uint64_t value(std::size_t pixel, HeatMetric metric) const;
};

/// Traces one primary ray per pixel centre through `accel` with intersect_counted, then
/// (unless stopped) times settings.timing_run_count passes of the same rays with plain
/// intersect for Mrays/s. Counters do not depend on the thread count.
HeatmapPanel trace_heatmap(std::string label, const Accel& accel, const Camera& camera,
                           const HeatmapSettings& settings, const RenderControl& control = {});

/// The panels side by side (panel i at x = i * width), coloured on one shared scale, each
/// labelled with its name, Mrays/s and work per ray, with a colour legend along the bottom.
/// Output size: (panel count * width) x height. Panels must share one size.
Image draw_heatmaps(std::span<const HeatmapPanel> panels, const HeatmapSettings& settings);

/// One line per panel for the terminal: totals and averages of nodes and triangles, Mrays/s.
std::string describe_heatmap_totals(const HeatmapPanel& panel);

}  // namespace rebraid::viewer
