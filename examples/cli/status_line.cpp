#include "status_line.h"

#include <unistd.h>

#include <cstdio>

namespace rebraid::cli {

StatusLine::StatusLine() : is_visible_(::isatty(STDERR_FILENO) == 1) {}

StatusLine::~StatusLine() {
    clear();
}

void StatusLine::show(const std::string& text) {
    if (!is_visible_) return;
    // Standard output first, so a result row is not drawn over the status line.
    std::fflush(stdout);
    // \r returns to the line start; \033[K clears what a longer previous line left.
    std::fprintf(stderr, "\r%s\033[K", text.c_str());
    std::fflush(stderr);
    is_shown_ = true;
}

void StatusLine::clear() {
    if (!is_shown_) return;
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    is_shown_ = false;
}

}  // namespace rebraid::cli
