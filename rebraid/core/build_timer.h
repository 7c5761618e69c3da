#pragma once

#include <chrono>

namespace rebraid {

/// Wall-clock time since construction, in milliseconds: what every builder reports as its
/// build time.
class BuildTimer {
public:
    double elapsed_ms() const {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
            .count();
    }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace rebraid
