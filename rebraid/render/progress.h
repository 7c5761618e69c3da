#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace rebraid::viewer {

/// A one-line progress bar with elapsed time and ETA on stderr, drawn only when stderr is a
/// terminal, so logs and pipes stay clean. `advance` may be called from many threads; the
/// bar redraws at most a few times per second.
class ProgressBar {
public:
    /// `total` units of work; `label` starts the line.
    ProgressBar(std::string label, std::uint64_t total);
    /// Finishes the line if `finish` was not called.
    ~ProgressBar();
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;

    /// Records `amount` more units done. Thread-safe.
    void advance(std::uint64_t amount);
    /// Draws the final state and ends the line. Idempotent.
    void finish();
    /// True when the bar is drawn (stderr is a terminal).
    bool is_visible() const { return is_visible_; }

private:
    using Clock = std::chrono::steady_clock;
    void draw(std::uint64_t done);

    std::string label_;
    std::uint64_t total_;
    bool is_visible_;
    std::atomic<std::uint64_t> done_{0};
    std::mutex draw_mutex_;  ///< one thread draws at a time; others skip
    Clock::time_point start_;
    Clock::time_point last_draw_;
    bool is_finished_ = false;
};

}  // namespace rebraid::viewer
