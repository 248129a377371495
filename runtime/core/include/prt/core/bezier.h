// PointRT core: bicubic Bezier patches in double precision (seed 002, 3 and 5.1): evaluation of
// Q, dQ/du, dQ/dv, d2Q/dudv, robust normals at degenerate points, de Casteljau subdivision, and the
// index arithmetic of the fixed-depth subpatch tree. Host and device (PRT_HD), no allocation.
#pragma once

#include <cmath>
#include <cstdint>

#include "prt/core/config.h"
#include "prt/core/math.h"
#include "prt/formats/patch_layout.h"

namespace prt::core {

/// A 3-vector of doubles (Newton iteration and hit points, seed 002, 5.3.3: double precision).
struct DVec3 {
    double x, y, z;
};

PRT_HD PRT_INLINE DVec3 dvec3(double x, double y, double z) {
    return DVec3{x, y, z};
}
PRT_HD PRT_INLINE DVec3 dvec3(const pool::PatchPoint& p) {
    return DVec3{p.x, p.y, p.z};
}
PRT_HD PRT_INLINE DVec3 dvec3(Vec3 v) {
    return DVec3{v.x, v.y, v.z};
}
PRT_HD PRT_INLINE Vec3 to_vec3(DVec3 a) {
    return Vec3{static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)};
}
PRT_HD PRT_INLINE DVec3 operator+(DVec3 a, DVec3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
PRT_HD PRT_INLINE DVec3 operator-(DVec3 a, DVec3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
PRT_HD PRT_INLINE DVec3 operator-(DVec3 a) {
    return {-a.x, -a.y, -a.z};
}
PRT_HD PRT_INLINE DVec3 operator*(DVec3 a, double s) {
    return {a.x * s, a.y * s, a.z * s};
}
PRT_HD PRT_INLINE DVec3 operator*(double s, DVec3 a) {
    return {a.x * s, a.y * s, a.z * s};
}
PRT_HD PRT_INLINE double dot(DVec3 a, DVec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
PRT_HD PRT_INLINE DVec3 cross(DVec3 a, DVec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
PRT_HD PRT_INLINE double length(DVec3 a) {
    return sqrt(dot(a, a));
}
PRT_HD PRT_INLINE bool is_finite(DVec3 a) {
    return a.x - a.x == 0.0 && a.y - a.y == 0.0 && a.z - a.z == 0.0;
}
// Plain comparisons (fmin / fmax are library calls on the host without -ffast-math); callers
// never pass NaN or handle it themselves.
PRT_HD PRT_INLINE double dmin(double a, double b) {
    return a < b ? a : b;
}
PRT_HD PRT_INLINE double dmax(double a, double b) {
    return a > b ? a : b;
}

/// Cubic Bernstein polynomials B_0..B_3 at t and their derivatives.
PRT_HD PRT_INLINE void bernstein3(double t, double b[4], double db[4]) {
    const double s = 1.0 - t;
    b[0] = s * s * s;
    b[1] = 3.0 * t * s * s;
    b[2] = 3.0 * t * t * s;
    b[3] = t * t * t;
    db[0] = -3.0 * s * s;
    db[1] = 3.0 * s * (s - 2.0 * t);
    db[2] = 3.0 * t * (2.0 * s - t);
    db[3] = 3.0 * t * t;
}

/// A patch and its first derivatives at one parameter (u, v).
struct PatchEval {
    DVec3 q;    ///< Q(u, v)
    DVec3 qu;   ///< dQ/du
    DVec3 qv;   ///< dQ/dv
    DVec3 quv;  ///< d2Q/dudv (for normals where dQ/du or dQ/dv vanishes)
};

/// seed 002, eq. 1: Q(u, v) = [U][M][P][M]^T[V]^T, evaluated in the Bernstein form with its
/// partial derivatives together (5.3.3: "evaluated together"). Parameters outside [0,1] evaluate
/// the polynomial's extension (Newton iterates may step slightly outside).
PRT_HD inline PatchEval patch_eval(const pool::PatchControlNet& net, double u, double v) {
    double bu[4], dbu[4], bv[4], dbv[4];
    bernstein3(u, bu, dbu);
    bernstein3(v, bv, dbv);
    PatchEval e{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    // Row by row, not unrolled on the device: unrolled, the compiler hoists all 48 coordinates out
    // of Newton's loop (96 registers per thread, spilled under the megakernel's register limit).
    // B_i(u) and B_i'(u) rotate through registers instead of being indexed by i.
    double b0 = bu[0], b1 = bu[1], b2 = bu[2], b3 = bu[3];
    double d0 = dbu[0], d1 = dbu[1], d2 = dbu[2], d3 = dbu[3];
#if defined(__CUDA_ARCH__)
    // A row's 4 points are 96 contiguous bytes: 16-byte loads where the net is 16-byte aligned
    // (device arrays are; each net is 384 bytes).
    const bool aligned16 = (reinterpret_cast<unsigned long long>(&net) & 15u) == 0;
#pragma unroll 1
#endif
    for (int i = 0; i < 4; ++i) {
        double c[12];  // x, y, z of the row's 4 points
#if defined(__CUDA_ARCH__)
        if (aligned16) {
            const double2* r = reinterpret_cast<const double2*>(&net.p[4 * i]);
#pragma unroll
            for (int k = 0; k < 6; ++k) {
                const double2 w = r[k];
                c[2 * k] = w.x;
                c[2 * k + 1] = w.y;
            }
        } else
#endif
        {
            PRT_UNROLL
            for (int j = 0; j < 4; ++j) {
                c[3 * j] = net.p[4 * i + j].x;
                c[3 * j + 1] = net.p[4 * i + j].y;
                c[3 * j + 2] = net.p[4 * i + j].z;
            }
        }
        DVec3 row{0, 0, 0}, drow{0, 0, 0};  // sum over v of this u-row, and its v-derivative
        PRT_UNROLL
        for (int j = 0; j < 4; ++j) {
            const DVec3 p{c[3 * j], c[3 * j + 1], c[3 * j + 2]};
            row = row + p * bv[j];
            drow = drow + p * dbv[j];
        }
        e.q = e.q + row * b0;
        e.qu = e.qu + row * d0;
        e.qv = e.qv + drow * b0;
        e.quv = e.quv + drow * d0;
        b0 = b1, b1 = b2, b2 = b3;
        d0 = d1, d1 = d2, d2 = d3;
    }
    return e;
}

/// Q, dQ/du and dQ/dv in single precision (the suite's float-versus-double trade, issue 9): the
/// same Bernstein form as patch_eval, with the control points rounded to float.
struct PatchEvalF {
    Vec3 q, qu, qv;
};

PRT_HD inline PatchEvalF patch_eval_f32(const pool::PatchControlNet& net, float u, float v) {
    const float su = 1.0f - u, sv = 1.0f - v;
    const float bu[4] = {su * su * su, 3.0f * u * su * su, 3.0f * u * u * su, u * u * u};
    const float dbu[4] = {-3.0f * su * su, 3.0f * su * (su - 2.0f * u), 3.0f * u * (2.0f * su - u), 3.0f * u * u};
    const float bv[4] = {sv * sv * sv, 3.0f * v * sv * sv, 3.0f * v * v * sv, v * v * v};
    const float dbv[4] = {-3.0f * sv * sv, 3.0f * sv * (sv - 2.0f * v), 3.0f * v * (2.0f * sv - v), 3.0f * v * v};
    PatchEvalF e{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    for (int i = 0; i < 4; ++i) {
        Vec3 row{0, 0, 0}, drow{0, 0, 0};
        PRT_UNROLL
        for (int j = 0; j < 4; ++j) {
            const pool::PatchPoint& c = net.p[4 * i + j];
            const Vec3 p{static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)};
            row = row + p * bv[j];
            drow = drow + p * dbv[j];
        }
        e.q = e.q + row * bu[i];
        e.qu = e.qu + row * dbu[i];
        e.qv = e.qv + drow * bu[i];
    }
    return e;
}

/// Size (relative to the control net's extent) under which a partial derivative counts as
/// vanished: a collapsed patch edge. Rounding leaves ~1e-16 there; 1e-9 from the edge the
/// derivative is already this small, and the limit normal used instead is off by O(1e-9).
inline constexpr double k_degenerate_derivative = 1e-9;

/// Largest coordinate range of the control net (the scale of "vanished" in patch_normal).
PRT_HD PRT_INLINE double net_extent(const pool::PatchControlNet& net) {
    DVec3 lo = dvec3(net.p[0]), hi = lo;
    for (int k = 1; k < 16; ++k) {
        lo = DVec3{dmin(lo.x, net.p[k].x), dmin(lo.y, net.p[k].y), dmin(lo.z, net.p[k].z)};
        hi = DVec3{dmax(hi.x, net.p[k].x), dmax(hi.y, net.p[k].y), dmax(hi.z, net.p[k].z)};
    }
    return dmax(hi.x - lo.x, dmax(hi.y - lo.y, hi.z - lo.z));
}

/// dQ/du x dQ/dv normalized, when both derivatives are above `eps` and not parallel.
PRT_HD PRT_INLINE bool regular_normal(DVec3 qu, DVec3 qv, double eps, DVec3& n) {
    const double lu = length(qu), lv = length(qv);
    if (!(lu > eps && lv > eps)) return false;
    const DVec3 c = cross(qu, qv);
    const double lc = length(c);
    if (!(lc > k_degenerate_derivative * lu * lv) || !is_finite(c)) return false;
    n = c * (1.0 / lc);
    return true;
}

/// Unit normal along dQ/du x dQ/dv at (u, v) (the orientation the patch's parametrization gives;
/// PatchInfo says whether it is consistent). Never NaN: where a partial derivative vanishes (the
/// teapot's collapsed lid and bottom edges) it takes the limit from inside the patch,
///   Q_u ~ (v - v_edge) Q_uv  =>  n ~ sign(v - v_edge) Q_uv x Q_v   (and likewise for Q_v),
/// then the normal at parameters moved towards the patch centre, and last `fallback`.
PRT_HD inline DVec3 patch_normal(const pool::PatchControlNet& net, double u, double v, const PatchEval& e,
                                 DVec3 fallback) {
    const double size = net_extent(net);
    if (!(size > 0.0) || !(size - size == 0.0)) return fallback;
    const double eps = k_degenerate_derivative * size;
    DVec3 n;
    if (regular_normal(e.qu, e.qv, eps, n)) return n;
    const double lu = length(e.qu), lv = length(e.qv);
    if (lu <= eps && lv > eps) {  // Q_u vanished: an edge v = const collapsed
        if (regular_normal(e.quv * (v < 0.5 ? 1.0 : -1.0), e.qv, eps, n)) return n;
    } else if (lv <= eps && lu > eps) {  // Q_v vanished: an edge u = const collapsed
        if (regular_normal(e.qu, e.quv * (u < 0.5 ? 1.0 : -1.0), eps, n)) return n;
    }
    // Corners where both derivatives vanish, or folds: a neighbouring parameter towards the centre.
    double step = 1e-4;
    for (int attempt = 0; attempt < 4; ++attempt, step *= 10.0) {
        const double un = u + step * (0.5 - u), vn = v + step * (0.5 - v);
        const PatchEval en = patch_eval(net, un, vn);
        if (regular_normal(en.qu, en.qv, eps, n)) return n;
    }
    return fallback;
}

/// de Casteljau split of a cubic (4 points, stride `s` apart) at t into [0,t] and [t,1] halves.
PRT_HD PRT_INLINE void de_casteljau_split(const pool::PatchPoint* in, int s, double t, pool::PatchPoint* lo,
                                          pool::PatchPoint* hi) {
    const DVec3 p0 = dvec3(in[0]), p1 = dvec3(in[s]), p2 = dvec3(in[2 * s]), p3 = dvec3(in[3 * s]);
    const double a = 1.0 - t;
    const DVec3 p01 = p0 * a + p1 * t, p12 = p1 * a + p2 * t, p23 = p2 * a + p3 * t;
    const DVec3 p012 = p01 * a + p12 * t, p123 = p12 * a + p23 * t;
    const DVec3 mid = p012 * a + p123 * t;
    const DVec3 l[4] = {p0, p01, p012, mid}, h[4] = {mid, p123, p23, p3};
    for (int k = 0; k < 4; ++k) {
        lo[k * s] = pool::PatchPoint{l[k].x, l[k].y, l[k].z};
        hi[k * s] = pool::PatchPoint{h[k].x, h[k].y, h[k].z};
    }
}

/// seed 002, 5.1: de Casteljau subdivision of a patch at parameter t along u (axis 0) or v (axis 1)
/// into the nets of its lower and upper halves, each reparametrized to [0,1]^2.
PRT_HD inline void patch_split(const pool::PatchControlNet& in, int axis, double t, pool::PatchControlNet& lo,
                               pool::PatchControlNet& hi) {
    for (int k = 0; k < 4; ++k) {
        if (axis == 0)  // the curves along u: column j = k, stride 4
            de_casteljau_split(in.p + k, 4, t, lo.p + k, hi.p + k);
        else  // the curves along v: row i = k, stride 1
            de_casteljau_split(in.p + 4 * k, 1, t, lo.p + 4 * k, hi.p + 4 * k);
    }
}

/// A rectangle of parameter space.
struct PatchDomain {
    double u0, u1, v0, v1;
};

/// Level of subpatch tree node k (root = 0): floor(log2(k + 1)).
PRT_HD PRT_INLINE std::uint32_t subpatch_level(std::uint32_t k) {
    std::uint32_t level = 0;
    for (std::uint32_t n = k + 1; n > 1; n >>= 1) ++level;
    return level;
}

/// Axis (0 = u, 1 = v) along which the nodes of `level` are split into their children: seed 002,
/// 5.1, "alternately subdividing it along the u and v axes", u first.
PRT_HD PRT_INLINE int subpatch_split_axis(std::uint32_t level) {
    return static_cast<int>(level & 1u);
}

/// Parameter domain of subpatch tree node k (level order, children 2k+1 = lower half, 2k+2 = upper
/// half): the node's path from the root is the binary digits of k + 1 after the leading one.
PRT_HD inline PatchDomain subpatch_domain(std::uint32_t k) {
    PatchDomain d{0.0, 1.0, 0.0, 1.0};
    const std::uint32_t level = subpatch_level(k);
    const std::uint32_t path = k + 1 - (1u << level);
    for (std::uint32_t s = 0; s < level; ++s) {
        const bool upper = ((path >> (level - 1 - s)) & 1u) != 0;
        if (subpatch_split_axis(s) == 0) {
            const double m = 0.5 * (d.u0 + d.u1);
            (upper ? d.u0 : d.u1) = m;
        } else {
            const double m = 0.5 * (d.v0 + d.v1);
            (upper ? d.v0 : d.v1) = m;
        }
    }
    return d;
}

/// One octahedral coordinate in [-1, 1] to 16 bits.
PRT_HD PRT_INLINE std::uint32_t octahedral_quantize(double c) {
    return static_cast<std::uint32_t>(floor((fmin(fmax(c, -1.0), 1.0) * 0.5 + 0.5) * 65535.0 + 0.5));
}

/// Octahedral encoding of a unit vector in 32 bits (16 bits per coordinate).
PRT_HD inline std::uint32_t octahedral_encode(DVec3 n) {
    const double l1 = fabs(n.x) + fabs(n.y) + fabs(n.z);
    double px = n.x / l1, py = n.y / l1;
    if (n.z < 0.0) {
        const double ox = (1.0 - fabs(py)) * (px >= 0.0 ? 1.0 : -1.0);
        const double oy = (1.0 - fabs(px)) * (py >= 0.0 ? 1.0 : -1.0);
        px = ox;
        py = oy;
    }
    return octahedral_quantize(px) | (octahedral_quantize(py) << 16);
}

/// Inverse of octahedral_encode (unit length).
PRT_HD inline DVec3 octahedral_decode(std::uint32_t code) {
    const double px = static_cast<double>(code & 0xffffu) / 65535.0 * 2.0 - 1.0;
    const double py = static_cast<double>(code >> 16) / 65535.0 * 2.0 - 1.0;
    DVec3 n{px, py, 1.0 - fabs(px) - fabs(py)};
    if (n.z < 0.0) {
        const double ox = (1.0 - fabs(py)) * (px >= 0.0 ? 1.0 : -1.0);
        const double oy = (1.0 - fabs(px)) * (py >= 0.0 ? 1.0 : -1.0);
        n.x = ox;
        n.y = oy;
    }
    return n * (1.0 / length(n));
}

}  // namespace prt::core
