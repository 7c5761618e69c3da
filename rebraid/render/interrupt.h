#pragma once

#include <atomic>

namespace rebraid::viewer {

/// While alive, Ctrl-C (SIGINT) raises a flag instead of ending the process, so a render can
/// stop at the next row and save what it has. A second Ctrl-C ends the process as usual.
/// The previous handler comes back on destruction. At most one guard may live at a time.
class InterruptGuard {
public:
    InterruptGuard();
    ~InterruptGuard();
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

    /// Becomes true at the first Ctrl-C (for RenderControl::stop_requested).
    const std::atomic<bool>& flag() const;
    bool is_interrupted() const { return flag().load(std::memory_order_relaxed); }
};

}  // namespace rebraid::viewer
