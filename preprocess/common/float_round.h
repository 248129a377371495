// PointRT preprocess: doubles rounded to float outwards, for boxes that must still enclose their
// double-precision contents once stored as floats (octree, MLS and patch bounds).
#pragma once

#include <cmath>
#include <limits>

namespace prt::pre {

/// `v` rounded to float, then towards -inf: the largest float not above `v`.
inline float round_down(double v) {
    float f = static_cast<float>(v);
    if (double(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}

/// `v` rounded to float, then towards +inf: the smallest float not below `v`.
inline float round_up(double v) {
    float f = static_cast<float>(v);
    if (double(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

}  // namespace prt::pre
