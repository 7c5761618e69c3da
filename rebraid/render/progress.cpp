#include "rebraid/render/progress.h"

#include <unistd.h>
#include <algorithm>
#include <cstdio>

#include <utility>

namespace rebraid::viewer {

namespace {

constexpr int kBarWidth = 30;
constexpr auto kRedrawInterval = std::chrono::milliseconds(100);

/// "12.3 s" or "2 min 05 s".
std::string format_duration(double seconds) {
    char text[32];
    if (seconds < 60.0) {
        std::snprintf(text, sizeof text, "%.1f s", seconds);
    } else {
        const auto whole = static_cast<long>(seconds);
        std::snprintf(text, sizeof text, "%ld min %02ld s", whole / 60, whole % 60);
    }
    return text;
}

}  // namespace

ProgressBar::ProgressBar(std::string label, std::uint64_t total)
    : label_(std::move(label)),
      total_(total),
      is_visible_(isatty(STDERR_FILENO) == 1),
      start_(Clock::now()),
      last_draw_(start_) {}

ProgressBar::~ProgressBar() {
    finish();
}

void ProgressBar::advance(std::uint64_t amount) {
    const std::uint64_t done = done_.fetch_add(amount, std::memory_order_relaxed) + amount;
    if (!is_visible_) return;
    // Whoever holds the lock draws; everybody else carries on working.
    std::unique_lock lock(draw_mutex_, std::try_to_lock);
    if (!lock.owns_lock() || is_finished_) return;
    const Clock::time_point now = Clock::now();
    if (now - last_draw_ < kRedrawInterval) return;
    last_draw_ = now;
    draw(done);
}

void ProgressBar::finish() {
    std::lock_guard lock(draw_mutex_);
    if (is_finished_) return;
    is_finished_ = true;
    if (!is_visible_) return;
    draw(done_.load(std::memory_order_relaxed));
    std::fputs("\n", stderr);
    std::fflush(stderr);
}

void ProgressBar::draw(std::uint64_t done) {
    const double fraction =
        total_ == 0 ? 1.0 : std::min(1.0, static_cast<double>(done) / static_cast<double>(total_));
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const int filled = static_cast<int>(fraction * kBarWidth);
    std::string bar(static_cast<std::size_t>(kBarWidth), ' ');
    std::fill_n(bar.begin(), filled, '#');

    std::string timing = format_duration(elapsed);
    if (fraction >= 1.0) {
        timing += " total";
    } else if (fraction > 0.0) {
        timing += ", ETA " + format_duration(elapsed * (1.0 - fraction) / fraction);
    }
    // \r returns to the line start; \033[K clears what a longer previous line left.
    std::fprintf(stderr, "\r%s [%s] %3d%%  %s\033[K", label_.c_str(), bar.c_str(),
                 static_cast<int>(fraction * 100.0), timing.c_str());
    std::fflush(stderr);
}

}  // namespace rebraid::viewer
