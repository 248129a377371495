// Test-only: double-precision 3-vectors for the independent references of the surface tests
// (iso_test_util.h, mls_test_util.h): conversions from the pool's and the core's float vectors,
// dot product and length.
#pragma once

#include <array>
#include <cmath>

#include "prt/core/math.h"
#include "prt/formats/pool_layout.h"

namespace prt::test {

using D3 = std::array<double, 3>;

inline D3 d3(const pool::Float3& f) {
    return {f.x, f.y, f.z};
}
inline D3 d3(const core::Vec3& v) {
    return {v.x, v.y, v.z};
}
inline double dot3(const D3& a, const D3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline double norm3(const D3& a) {
    return std::sqrt(dot3(a, a));
}

}  // namespace prt::test
