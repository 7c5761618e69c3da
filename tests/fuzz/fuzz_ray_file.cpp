// libFuzzer target: the ray-file reader (rebraid/io/ray_file.h) on arbitrary text.
// Every input must either throw rebraid::Error or give rays that satisfy the documented
// rules, and those rays must survive write_rays -> read_rays unchanged.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/io/ray_file.h"

namespace {

/// The rules read_rays promises for every ray it returns (ray_file.h).
bool follows_rules(const rebraid::Ray& ray) {
    const bool zero_dir = ray.dir.x == 0.0f && ray.dir.y == 0.0f && ray.dir.z == 0.0f;
    return rebraid::is_finite(ray.org) && rebraid::is_finite(ray.dir) && !zero_dir &&
           std::isfinite(ray.tnear) && ray.tnear >= 0.0f && !std::isnan(ray.tfar) &&
           ray.tfar != -INFINITY;
}

bool same_bits(const rebraid::Ray& a, const rebraid::Ray& b) {
    return a.org.x == b.org.x && a.org.y == b.org.y && a.org.z == b.org.z && a.dir.x == b.dir.x &&
           a.dir.y == b.dir.y && a.dir.z == b.dir.z && a.tnear == b.tnear && a.tfar == b.tfar &&
           std::signbit(a.tnear) == std::signbit(b.tnear);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    std::vector<rebraid::Ray> rays;
    try {
        rays = rebraid::read_rays(in, "fuzz");
    } catch (const rebraid::Error&) {
        return 0;  // a documented rejection
    }
    for (const rebraid::Ray& ray : rays)
        if (!follows_rules(ray)) std::abort();
    std::ostringstream out;
    rebraid::write_rays(out, rays);
    std::istringstream again(out.str());
    const std::vector<rebraid::Ray> reread = rebraid::read_rays(again, "rewritten");
    if (reread.size() != rays.size()) std::abort();
    for (std::size_t i = 0; i < rays.size(); ++i)
        if (!same_bits(rays[i], reread[i])) std::abort();
    return 0;
}
