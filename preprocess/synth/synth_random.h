// PointRT synthetic models, internal: deterministic randomness for prt-synth (sampling and scans).
// Every value is a pure function of (seed, stream, indices), so the output never depends on how the
// work is split between threads.
#pragma once

#include <cmath>
#include <cstdint>

#include "synth.h"

namespace prt::synth::detail {

/// SplitMix64's finaliser (Steele, Lea and Flood 2014): a bijective 64-bit mix with full avalanche.
inline std::uint64_t mix(std::uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
inline std::uint64_t hash(std::uint64_t seed, std::uint64_t stream, std::uint64_t a, std::uint64_t b = 0) {
    return mix(mix(mix(mix(seed) ^ stream) ^ a) ^ b);
}
/// [0, 1) from the top 53 bits.
inline double unit(std::uint64_t x) {
    return static_cast<double>(x >> 11) * 0x1.0p-53;
}

/// A counter-based stream (SplitMix64) for one point or ray.
struct Stream {
    std::uint64_t state;
    std::uint64_t next() { return mix(state += 0x9E3779B97F4A7C15ull); }
    double uniform() { return unit(next()); }
};

/// Standard normal, truncated at k_noise_truncation by redrawing (Box-Muller).
inline double truncated_gaussian(Stream& s) {
    constexpr double k_two_pi = 6.28318530717958647692;
    for (;;) {
        const double u1 = 1.0 - s.uniform();  // (0, 1]
        const double u2 = s.uniform();
        const double g = std::sqrt(-2.0 * std::log(u1)) * std::cos(k_two_pi * u2);
        if (std::fabs(g) <= k_noise_truncation) return g;
    }
}

// Stream numbers: sampling (synth.cpp) 1-3, scans (scan.cpp) 16-31.
inline constexpr std::uint64_t k_stream_shift = 1;   ///< per-patch R2 shifts
inline constexpr std::uint64_t k_stream_random = 2;  ///< per-point (u, v) for Sampling::random
inline constexpr std::uint64_t k_stream_noise = 3;   ///< per-point noise

}  // namespace prt::synth::detail
