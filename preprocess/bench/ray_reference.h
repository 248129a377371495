// PointRT: the two ray tests of the independent references, in double (header-only, host): a ray
// against an axis-aligned box (the slab test, Kay and Kajiya 1986) and against a triangle (Moller
// and Trumbore 1997, both faces). Shared by prt-accuracy's and prt-fidelity's ground truth
// (prt_accuracy.cpp, mesh_reference.cpp) and the tests' brute-force references.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>

#include "prt/vec3.h"

namespace prt::bench {

/// Narrows [t0, t1] to the part of the ray o + t d inside the box [lo, hi] (any 3 numbers by index).
/// A direction component of 0 keeps the ray only where o lies within that slab. False when the
/// part is empty.
template <class Box>
bool clip_to_box(const Vec3d& o, const Vec3d& d, const Box& lo, const Box& hi, double& t0, double& t1) {
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0) {
            if (o[a] < lo[a] || o[a] > hi[a]) return false;
            continue;
        }
        double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

/// Where the line o + t d meets triangle abc (either face): its t (any sign) and the barycentrics u
/// (weight of b) and v (weight of c). False where it passes outside the triangle or runs parallel
/// to its plane (determinant 0 or of magnitude below `min_abs_det`).
inline bool ray_triangle(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                         double min_abs_det, double& t, double& u, double& v) {
    const Vec3d e1 = sub(b, a), e2 = sub(c, a);
    const Vec3d p = cross(d, e2);
    const double det = dot(e1, p);
    if (det == 0 || std::fabs(det) < min_abs_det) return false;
    const double inv_det = 1.0 / det;
    const Vec3d s = sub(o, a);
    u = dot(s, p) * inv_det;
    if (u < 0 || u > 1) return false;
    const Vec3d q = cross(s, e1);
    v = dot(d, q) * inv_det;
    if (v < 0 || u + v > 1) return false;
    t = dot(e2, q) * inv_det;
    return true;
}

}  // namespace prt::bench
