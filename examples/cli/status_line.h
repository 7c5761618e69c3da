#pragma once

#include <string>

namespace rebraid::cli {

/// One line on standard error saying what a long command is doing now ("bench: crown.glb:
/// rebraid (2/5): diffuse rays"), redrawn in place. Drawn only when standard error is a
/// terminal, so pipes and logs stay clean; cleared before results go to standard output and
/// when it goes out of scope.
class StatusLine {
public:
    StatusLine();
    ~StatusLine();
    StatusLine(const StatusLine&) = delete;
    StatusLine& operator=(const StatusLine&) = delete;

    /// Replaces the line with `text`.
    void show(const std::string& text);
    /// Removes the line, so the next output starts on a clean line.
    void clear();
    /// True when the line is drawn (standard error is a terminal).
    bool is_visible() const { return is_visible_; }

private:
    bool is_visible_;
    bool is_shown_ = false;
};

}  // namespace rebraid::cli
