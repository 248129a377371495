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

/// The mean unit normal of the splats [begin, end) of `src` that can ever be hit (intersect_splat
/// needs r*r > 0 and dot(d, n) != 0): 1 and `axis` set, 0 when there is none, -1 when any such
/// splat is not finite (the leaf's bounds must then be open).
template <class Src>
PRT_HD PRT_INLINE int leaf_mean_normal(const Src& src, std::uint32_t begin, std::uint32_t end,
                                       double axis[3]) {
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
            return -1;
        const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int a = 0; a < 3; ++a) sum[a] += n[a] / len;
        ++hittable;
    }
    if (hittable == 0) return 0;
    axis[0] = 0;
    axis[1] = 0;
    axis[2] = 1;
    const double slen = sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    if (slen > 1e-6 * hittable)
        for (int a = 0; a < 3; ++a) axis[a] = sum[a] / slen;
    return 1;
}

/// The cone and slab of the hittable splats [begin, end) of `src` about `af` exactly as the tests
/// read it (splat.h, bounds_may_hit: dot(af, d) and dot(af, p) in float, af of any length), in
/// double: `threshold` on dot(af, d) / |d| (sin(theta) of the widest normal plus a margin of 1e-4,
/// times |af|; 2 |af| when the normals do not fit a cone narrower than a half-space) and the slab
/// [lo, hi] of dot(af, p) over every disk point, widened by a relative 1e-6. A disk of radius r, unit
/// normal n spans r sqrt(|af|^2 - (af.n)^2) either side of its centre's dot(af, c).
struct LeafExtent {
    double threshold, lo, hi;
};
template <class Src>
PRT_HD PRT_INLINE LeafExtent leaf_extent(const Src& src, std::uint32_t begin, std::uint32_t end,
                                         const float af[3]) {
    const double dinf = static_cast<double>(k_inf);
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
            af[0] * double(s.position.x) + af[1] * double(s.position.y) + af[2] * double(s.position.z);
        const double extent = fabs(double(s.radius)) * alen * sqrt(fmax(0.0, 1.0 - c * c));
        lo = centre - extent < lo ? centre - extent : lo;
        hi = centre + extent > hi ? centre + extent : hi;
        scale = fmax(fmax(fmax(scale, fabs(double(s.position.x))),
                          fmax(fabs(double(s.position.y)), fabs(double(s.position.z)))),
                     fabs(double(s.radius)));
    }
    // Cone: normals within theta of the axis, cos(theta) = min_cos; a half-space or more never passes.
    LeafExtent x;
    x.threshold = min_cos > 1e-3 ? (sqrt(fmax(0.0, 1.0 - min_cos * min_cos)) + 1e-4) * alen : 2.0 * alen;
    const double margin = 1e-6 * scale * alen + 1e-6 * fmax(fabs(lo), fabs(hi));
    x.lo = lo - margin;
    x.hi = hi + margin;
    return x;
}

/// The bounds of splats [begin, end) of `src` (anything with `pool::Splat load(i)`: SplatArray,
/// bricks.h's BrickSplats); begin/end of the result are left 0 for the caller to set. The cone
/// axis is the mean unit normal (leaf_mean_normal), rounded to float; the cone and slab are about
/// that float vector (leaf_extent), rounded outward to float.
template <class Src>
PRT_HD PRT_INLINE LeafBounds leaf_bounds_of(const Src& src, std::uint32_t begin, std::uint32_t end) {
    double axis[3];
    const int mean = leaf_mean_normal(src, begin, end, axis);
    if (mean < 0) return open_leaf_bounds();
    if (mean == 0) return LeafBounds{0.0f, 0.0f, 1.0f, -1.0f, 1.0f, -1.0f, 0u, 0u};  // every ray passes
    const float af[3] = {static_cast<float>(axis[0]), static_cast<float>(axis[1]),
                         static_cast<float>(axis[2])};
    const LeafExtent x = leaf_extent(src, begin, end, af);
    LeafBounds b{};
    b.axis_x = af[0];
    b.axis_y = af[1];
    b.axis_z = af[2];
    b.sin_theta = x.threshold >= 2.0 ? 2.0f : nextafterf(static_cast<float>(x.threshold), k_inf);
    b.lo = nextafterf(static_cast<float>(x.lo), -k_inf);
    b.hi = nextafterf(static_cast<float>(x.hi), k_inf);
    return b;
}

/// leaf_bounds_of in 16 bytes (octree.h, BrickLeafBounds, for the leaves of bricks): the mean
/// normal rounded to integers at scale 32767, the cone and slab built about that integer vector
/// (leaf_extent), the threshold rounded up to an integer (never passing when it does not fit 16
/// bits), the slab outward to float.
template <class Src>
PRT_HD PRT_INLINE BrickLeafBounds brick_leaf_bounds_of(const Src& src, std::uint32_t begin,
                                                       std::uint32_t end) {
    BrickLeafBounds b{};
    b.axis_z = static_cast<std::int16_t>(k_brick_axis_scale);
    double axis[3];
    const int mean = leaf_mean_normal(src, begin, end, axis);
    if (mean <= 0) {  // open bounds (every ray reads the leaf), or none hittable (every ray passes)
        b.sin_code = mean < 0 ? k_brick_cone_never : 0u;
        b.lo = mean < 0 ? -k_inf : 1.0f;
        b.hi = mean < 0 ? k_inf : -1.0f;
        return b;
    }
    const std::int16_t q[3] = {static_cast<std::int16_t>(llrint(axis[0] * k_brick_axis_scale)),
                               static_cast<std::int16_t>(llrint(axis[1] * k_brick_axis_scale)),
                               static_cast<std::int16_t>(llrint(axis[2] * k_brick_axis_scale))};
    const float af[3] = {float(q[0]), float(q[1]), float(q[2])};
    const LeafExtent x = leaf_extent(src, begin, end, af);
    b.axis_x = q[0];
    b.axis_y = q[1];
    b.axis_z = q[2];
    b.sin_code = x.threshold >= double(k_brick_cone_never) ? k_brick_cone_never
                                                           : static_cast<std::uint16_t>(ceil(x.threshold));
    b.lo = nextafterf(static_cast<float>(x.lo), -k_inf);
    b.hi = nextafterf(static_cast<float>(x.hi), k_inf);
    return b;
}

}  // namespace prt::core
