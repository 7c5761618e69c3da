#pragma once

#include <atomic>
#include <functional>
#include <vector>

namespace rebraid::viewer {

/// Called from worker threads with the number of image rows just finished; must be
/// thread-safe. Used for progress display.
using RowsDoneCallback = std::function<void(int row_count)>;

/// How a caller follows and stops a render.
struct RenderControl {
    /// Progress, or empty.
    RowsDoneCallback on_rows_done;
    /// When set and it becomes true, no further rows are started (rows under way finish);
    /// the result then holds the rows done so far. Null: run to the end.
    const std::atomic<bool>* stop_requested = nullptr;
};

/// Runs `render_row(y)` for every row y in [0, height), rows in parallel (TBB), until the
/// control's stop flag is raised. Marks each finished row in `row_is_done` (resized to
/// `height`) and returns how many rows finished. What a row computes must not depend on
/// which thread runs it.
int for_each_row(int height, const RenderControl& control,
                 const std::function<void(int y)>& render_row, std::vector<char>& row_is_done);

}  // namespace rebraid::viewer
