// PointRT preprocess: doubles rounded to float outwards, for boxes that must still enclose their
// double-precision contents once stored as floats (octree, MLS and patch bounds).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace prt::pre {

/// std::nextafter(f, -inf) for a float that is not NaN nor -inf, on its bits (glibc's nextafterf is
/// an out-of-line call: 4 % of the out-of-core brick build's partition passes, which round every
/// point's disk box).
inline float next_float_down(float f) {
    if (f == 0.0f) return -std::numeric_limits<float>::denorm_min();
    const std::uint32_t u = std::bit_cast<std::uint32_t>(f);
    return std::bit_cast<float>(f > 0.0f ? u - 1u : u + 1u);
}

/// std::nextafter(f, +inf) for a float that is not NaN nor +inf.
inline float next_float_up(float f) {
    if (f == 0.0f) return std::numeric_limits<float>::denorm_min();
    const std::uint32_t u = std::bit_cast<std::uint32_t>(f);
    return std::bit_cast<float>(f > 0.0f ? u + 1u : u - 1u);
}

/// `v` rounded to float, then towards -inf: the largest float not above `v`.
inline float round_down(double v) {
    float f = static_cast<float>(v);
    if (double(f) > v) f = next_float_down(f);  // f > v: not NaN, not -inf
    return f;
}

/// `v` rounded to float, then towards +inf: the smallest float not below `v`.
inline float round_up(double v) {
    float f = static_cast<float>(v);
    if (double(f) < v) f = next_float_up(f);  // f < v: not NaN, not +inf
    return f;
}

}  // namespace prt::pre
