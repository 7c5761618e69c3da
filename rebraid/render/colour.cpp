#include "rebraid/render/colour.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace rebraid::viewer {

namespace {

struct RampStop {
    float at;
    Vec3f colour;  ///< display values
};

// Chosen so brightness grows with the value: readable in grey print too.
constexpr std::array kHeatRamp{
    RampStop{0.00f, {0.05f, 0.03f, 0.20f}}, RampStop{0.20f, {0.12f, 0.25f, 0.75f}},
    RampStop{0.40f, {0.05f, 0.62f, 0.72f}}, RampStop{0.60f, {0.45f, 0.83f, 0.25f}},
    RampStop{0.80f, {0.98f, 0.75f, 0.10f}}, RampStop{0.92f, {0.92f, 0.27f, 0.10f}},
    RampStop{1.00f, {1.00f, 0.94f, 0.90f}},
};

}  // namespace

float linear_to_srgb(float linear) {
    const float c = std::clamp(linear, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

Vec3f linear_to_srgb(Vec3f linear) {
    return {linear_to_srgb(linear.x), linear_to_srgb(linear.y), linear_to_srgb(linear.z)};
}

float srgb_to_linear(float encoded) {
    const float c = std::clamp(encoded, 0.0f, 1.0f);
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

Vec3f srgb_to_linear(Vec3f encoded) {
    return {srgb_to_linear(encoded.x), srgb_to_linear(encoded.y), srgb_to_linear(encoded.z)};
}

Vec3f heat_colour(float fraction) {
    const float f = std::isfinite(fraction) ? std::clamp(fraction, 0.0f, 1.0f) : 0.0f;
    for (std::size_t i = 1; i < kHeatRamp.size(); ++i) {
        if (f <= kHeatRamp[i].at) {
            const RampStop& a = kHeatRamp[i - 1];
            const RampStop& b = kHeatRamp[i];
            const float w = (f - a.at) / (b.at - a.at);
            return a.colour + (b.colour - a.colour) * w;
        }
    }
    return kHeatRamp.back().colour;
}

}  // namespace rebraid::viewer
