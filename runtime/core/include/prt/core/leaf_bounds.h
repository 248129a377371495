// PointRT core: the bounds of one filled octree leaf (octree.h, LeafBounds: a normal cone and a slab
// along its axis), computed from the leaf's splats, host and device alike: the host derives them
// when a scene is loaded (rt::build_leaf_bounds) and the CUDA brick storage on the GPU when a
// streamed brick arrives (issue 17), with the same arithmetic (double precision, outward rounding).
#pragma once

#include <cstdint>

#include "prt/core/config.h"
#include "prt/core/math.h"
#include "prt/core/octree.h"

namespace prt::core {

/// A leaf whose splats the tests must always read (non-finite data).
PRT_HD PRT_INLINE LeafBounds open_leaf_bounds() {
    return LeafBounds{0.0f, 0.0f, 1.0f, 2.0f, -k_inf, k_inf, 0u, 0u};
}

/// Whether `v` is finite (false for NaN and +-Inf).
PRT_HD PRT_INLINE bool finite_double(double v) {
    return v - v == 0.0;
}

/// Splats in an array (OctreeView::splats), as leaf_bounds_of reads them.
struct SplatArray {
    const pool::Splat* splats;
    PRT_HD PRT_INLINE pool::Splat load(std::uint32_t i) const { return splats[i]; }
};

/// The bounds of splats [begin, end) of `src` (anything with `pool::Splat load(i)`: SplatArray,
/// bricks.h's BrickSplats); begin/end of the result are left 0 for the caller to set.
///   Pass 1: which splats can ever be hit (intersect_splat needs r*r > 0 and dot(d, n) != 0) and
///           the mean of their unit normals, the cone axis; any non-finite splat: open bounds.
///   Pass 2: the widest normal from the axis (the cone) and the extent of every disk along the
///           axis (the slab): a disk of radius r, unit normal n spans r sqrt(1 - (a.n)^2) either
///           side of its centre along the unit axis a.
/// The cone gets a margin of 1e-4 on sin(theta) and the slab a relative 1e-6 rounded outward to
/// float, covering the float arithmetic of the tests (splat.h, leaf_may_hit).
template <class Src>
PRT_HD PRT_INLINE LeafBounds leaf_bounds_of(const Src& src, std::uint32_t begin, std::uint32_t end) {
    const double dinf = static_cast<double>(k_inf);
    double sum[3] = {0, 0, 0};
    std::uint32_t hittable = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = src.load(i);
        const float r2 = s.radius * s.radius;
        const double n[3] = {s.normal.x, s.normal.y, s.normal.z};
        if (!(r2 > 0.0f) || n[0] != n[0] || n[1] != n[1] || n[2] != n[2]) continue;
        if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) continue;
        if (!finite_double(s.radius) || !finite_double(s.position.x) || !finite_double(s.position.y) ||
            !finite_double(s.position.z) || !finite_double(n[0]) || !finite_double(n[1]) ||
            !finite_double(n[2]))
            return open_leaf_bounds();
        const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int a = 0; a < 3; ++a) sum[a] += n[a] / len;
        ++hittable;
    }
    if (hittable == 0) return LeafBounds{0.0f, 0.0f, 1.0f, -1.0f, 1.0f, -1.0f, 0u, 0u};  // every ray passes
    double axis[3] = {0, 0, 1};
    const double slen = sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    if (slen > 1e-6 * hittable)
        for (int a = 0; a < 3; ++a) axis[a] = sum[a] / slen;
    // The axis as the tests read it (float), renormalized in double: cone and slab are about
    // exactly the stored vector.
    const float af[3] = {static_cast<float>(axis[0]), static_cast<float>(axis[1]),
                         static_cast<float>(axis[2])};
    const double alen = sqrt(double(af[0]) * af[0] + double(af[1]) * af[1] + double(af[2]) * af[2]);
    double min_cos = dinf, lo = dinf, hi = -dinf, scale = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = src.load(i);
        const double n[3] = {s.normal.x, s.normal.y, s.normal.z};
        if (!(s.radius * s.radius > 0.0f) || n[0] != n[0] || n[1] != n[1] || n[2] != n[2]) continue;
        if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) continue;
        const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const double c = (af[0] * n[0] + af[1] * n[1] + af[2] * n[2]) / (len * alen);
        min_cos = c < min_cos ? c : min_cos;
        const double centre =
            (af[0] * double(s.position.x) + af[1] * double(s.position.y) + af[2] * double(s.position.z)) /
            alen;
        const double extent = fabs(double(s.radius)) * sqrt(fmax(0.0, 1.0 - c * c));
        lo = centre - extent < lo ? centre - extent : lo;
        hi = centre + extent > hi ? centre + extent : hi;
        scale = fmax(fmax(fmax(scale, fabs(double(s.position.x))),
                          fmax(fabs(double(s.position.y)), fabs(double(s.position.z)))),
                     fabs(double(s.radius)));
    }
    LeafBounds b{};
    b.axis_x = af[0];
    b.axis_y = af[1];
    b.axis_z = af[2];
    // Cone: normals within theta of the axis, cos(theta) = min_cos; a half-space or more never passes.
    b.sin_theta = min_cos > 1e-3 ? static_cast<float>(sqrt(fmax(0.0, 1.0 - min_cos * min_cos)) + 1e-4) : 2.0f;
    const double margin = 1e-6 * scale + 1e-6 * fmax(fabs(lo), fabs(hi));
    b.lo = nextafterf(static_cast<float>(lo - margin), -k_inf);
    b.hi = nextafterf(static_cast<float>(hi + margin), k_inf);
    return b;
}

}  // namespace prt::core
