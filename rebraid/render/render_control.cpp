#include "rebraid/render/render_control.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

namespace rebraid::viewer {

int for_each_row(int height, const RenderControl& control,
                 const std::function<void(int y)>& render_row, std::vector<char>& row_is_done) {
    row_is_done.assign(static_cast<std::size_t>(std::max(0, height)), 0);
    // Small chunks: rows differ a lot in cost, and a stop request takes effect quickly.
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 2),
                      [&](const tbb::blocked_range<int>& rows) {
                          int finished = 0;
                          for (int y = rows.begin(); y != rows.end(); ++y) {
                              if (control.stop_requested &&
                                  control.stop_requested->load(std::memory_order_relaxed))
                                  break;
                              render_row(y);
                              row_is_done[static_cast<std::size_t>(y)] = 1;
                              ++finished;
                          }
                          if (finished > 0 && control.on_rows_done) control.on_rows_done(finished);
                      });
    int done = 0;
    for (char is_done : row_is_done) done += is_done;
    return done;
}

}  // namespace rebraid::viewer
