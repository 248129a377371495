// PointRT core: doubles rounded to float outwards, for boxes that must still enclose their
// double-precision contents once stored as floats (the octree builders' disk boxes on the CPU and
// the GPU, MLS and patch bounds through preprocess/common/float_round.h). Host and device.
#pragma once

#include <bit>
#include <cstdint>

#include "prt/core/config.h"

namespace prt::core {

PRT_HD PRT_INLINE std::uint32_t float_to_bits(float f) {
#if PRT_DEVICE_CODE
    return __float_as_uint(f);
#else
    return std::bit_cast<std::uint32_t>(f);
#endif
}
PRT_HD PRT_INLINE float bits_to_float(std::uint32_t u) {
#if PRT_DEVICE_CODE
    return __uint_as_float(u);
#else
    return std::bit_cast<float>(u);
#endif
}

/// std::nextafter(f, -inf) for a float that is not NaN nor -inf, on its bits (glibc's nextafterf is
/// an out-of-line call: 4 % of the out-of-core brick build's partition passes, which round every
/// point's disk box).
PRT_HD PRT_INLINE float next_float_down(float f) {
    if (f == 0.0f) return -bits_to_float(1u);  // -denorm_min
    const std::uint32_t u = float_to_bits(f);
    return bits_to_float(f > 0.0f ? u - 1u : u + 1u);
}

/// std::nextafter(f, +inf) for a float that is not NaN nor +inf.
PRT_HD PRT_INLINE float next_float_up(float f) {
    if (f == 0.0f) return bits_to_float(1u);  // denorm_min
    const std::uint32_t u = float_to_bits(f);
    return bits_to_float(f > 0.0f ? u + 1u : u - 1u);
}

/// `v` rounded to float, then towards -inf: the largest float not above `v`.
PRT_HD PRT_INLINE float round_down(double v) {
    float f = static_cast<float>(v);
    if (double(f) > v) f = next_float_down(f);  // f > v: not NaN, not -inf
    return f;
}

/// `v` rounded to float, then towards +inf: the smallest float not below `v`.
PRT_HD PRT_INLINE float round_up(double v) {
    float f = static_cast<float>(v);
    if (double(f) < v) f = next_float_up(f);  // f < v: not NaN, not +inf
    return f;
}

}  // namespace prt::core
