#pragma once

#include <cstdint>

namespace rebraid {

/// Small deterministic pseudo-random generator (PCG32: 64-bit LCG state, permuted 32-bit
/// output). Written here rather than taken from <random> so a seed gives the same stream on
/// every standard library, compiler and machine; no std distributions are used either.
class Random {
public:
    /// Different seeds give independent-looking streams; the same seed gives the same stream.
    explicit Random(std::uint64_t seed) {
        // Derive the stream increment from the seed as well, so nearby seeds differ in more
        // than their first outputs. The increment must be odd for a full-period LCG.
        increment_ = (mix(seed ^ 0x9e3779b97f4a7c15ull) << 1u) | 1u;
        state_ = 0;
        next_u32();
        state_ += mix(seed);
        next_u32();
    }

    /// Uniform over all 32-bit values.
    std::uint32_t next_u32() {
        const std::uint64_t old = state_;
        state_ = old * 6364136223846793005ull + increment_;
        // PCG "XSH RR": xorshift the high bits down, then rotate by the top 5 bits.
        const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
        const auto rotation = static_cast<std::uint32_t>(old >> 59u);
        return (xorshifted >> rotation) | (xorshifted << ((32u - rotation) & 31u));
    }

    /// Uniform in [0, 1): the top 24 bits scaled by 2^-24, so every value is exact in float
    /// and 1 is never returned.
    float next_float01() { return static_cast<float>(next_u32() >> 8u) * 0x1.0p-24f; }

    /// Uniform in [lo, hi).
    float next_float(float lo, float hi) { return lo + (hi - lo) * next_float01(); }

    /// Uniform integer in [0, bound) for bound > 0 (multiply-shift; the bias is below 2^-32
    /// per value for the small bounds the project uses).
    std::uint32_t next_below(std::uint32_t bound) {
        return static_cast<std::uint32_t>((static_cast<std::uint64_t>(next_u32()) * bound) >> 32u);
    }

private:
    /// splitmix64 finalizer: spreads seed bits over the whole word.
    static std::uint64_t mix(std::uint64_t z) {
        z = (z ^ (z >> 30u)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27u)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31u);
    }

    std::uint64_t state_ = 0;
    std::uint64_t increment_ = 1;
};

}  // namespace rebraid
