// PointRT core: the exact overlap test between a splat (an oriented disk) and an axis-aligned
// box, used to replicate splats into every octree leaf they touch (thesis 3.4, after [LMR07]), and the
// octree builder's classification of a disk into a node's children built on it. Shared by the CPU
// builder (preprocess/splat/octree_build.cpp, prt-iso) and the CUDA one (runtime/cuda/src/octree_build.cu):
// plain double arithmetic, compiled without FMA contraction on both, so both decide every child alike.
//
// Derivation. The disk is D = {x : n.(x - c) = 0, |x - c| <= r} with |n| = 1; the box is
// B = [lo, hi]. D and B intersect iff the plane P = {n.(x - c) = 0} cuts B and the part of B in P
// (a convex polygon) comes within r of c, that is iff the convex problem
//
//     d^2 = min |x - c|^2   subject to   x in B,  n.(x - c) = 0
//
// is feasible with d <= r. Relax the one equality with a multiplier: for fixed lambda,
// min_{x in B} |x - c|^2 + 2 lambda n.(x - c) separates per axis and is solved by
//
//     x(lambda) = clamp(c - lambda n, lo, hi).
//
// The dual derivative is proportional to g(lambda) = n.(x(lambda) - c) = sum_i n_i (x_i(lambda) - c_i).
// Each term is continuous, piecewise linear and non-increasing in lambda (slope -n_i^2 while
// unclamped, 0 while clamped), so g is too, with at most 6 breakpoints lambda = (c_i - lo_i)/n_i and
// (c_i - hi_i)/n_i. g(-inf) = max_{x in B} n.(x - c) and g(+inf) = min_{x in B} n.(x - c): the plane
// cuts the box iff g(+inf) <= 0 <= g(-inf). Then g has a root lambda* (found exactly on the linear
// piece between two sorted breakpoints), and since the problem is convex with linear constraints
// (strong duality, strictly convex objective), x(lambda*) is the closest point of P n B to c.
// Overlap iff |x(lambda*) - c| <= r. Everything is evaluated in double precision.
//
// Closed sets on both sides: a disk that only touches a box face, edge or corner overlaps it.
#pragma once

#include <cmath>
#include <cstdint>

#include "prt/core/config.h"
#include "prt/core/float_round.h"
#include "prt/core/morton.h"
#include "prt/formats/pool_layout.h"

namespace prt::core {

/// std::max / std::min / std::clamp of doubles with their exact tie and signed-zero behaviour,
/// callable from device code (fmax and fmin may return either zero).
PRT_HD PRT_INLINE double exact_max(double a, double b) {
    return a < b ? b : a;
}
PRT_HD PRT_INLINE double exact_min(double a, double b) {
    return b < a ? b : a;
}
PRT_HD PRT_INLINE double exact_clamp(double v, double lo, double hi) {
    return v < lo ? lo : (hi < v ? hi : v);
}

/// Squared distance from `c` to the closest point of (plane through c with unit normal n) n (box
/// [lo, hi]), or a negative value when the plane misses the box. See the derivation above.
PRT_HD inline double plane_box_distance_sq(const double c[3], const double n[3], const double lo[3],
                                           const double hi[3]) {
    // g(+inf) and g(-inf): the plane must separate the box's extreme corners along n.
    double g_max = 0, g_min = 0;
    for (int i = 0; i < 3; ++i) {
        const double a = n[i] * (lo[i] - c[i]), b = n[i] * (hi[i] - c[i]);
        g_max += exact_max(a, b);
        g_min += exact_min(a, b);
    }
    if (g_min > 0 || g_max < 0) return -1.0;
    // Sweep lambda upwards over the breakpoints. Axis i is unclamped on [enter_i, leave_i], where
    // its term of g has slope -n_i^2; elsewhere the term is constant. Left of every breakpoint
    // g = g_max >= 0; the root lies on the first piece where g reaches 0.
    struct Event {
        double at;
        double slope_change;
    };
    Event events[6];
    int count = 0;
    for (int i = 0; i < 3; ++i) {
        if (n[i] == 0) continue;
        const double t0 = (c[i] - lo[i]) / n[i], t1 = (c[i] - hi[i]) / n[i];
        const double n2 = n[i] * n[i];
        events[count++] = {exact_min(t0, t1), -n2};
        events[count++] = {exact_max(t0, t1), +n2};
    }
    for (int k = 1; k < count; ++k)  // insertion sort of at most 6 events
        for (int j = k; j > 0 && events[j - 1].at > events[j].at; --j) {
            const Event e = events[j - 1];
            events[j - 1] = events[j];
            events[j] = e;
        }
    double lambda = count > 0 ? events[count - 1].at : 0.0;
    if (count > 0) {
        double g = g_max, slope = 0;
        lambda = events[0].at;
        for (int k = 0; k < count && g > 0; ++k) {
            slope += events[k].slope_change;
            const double next = k + 1 < count ? events[k + 1].at : events[k].at;
            const double g_next = g + slope * (next - events[k].at);
            if (g_next <= 0 || k + 1 == count) {
                // root on [events[k].at, next]; slope < 0 here since g decreases to <= 0
                lambda = slope < 0 ? events[k].at + g / -slope : next;
                if (k + 1 < count) lambda = exact_min(lambda, next);
                break;
            }
            g = g_next;
            lambda = next;
        }
    }
    double d2 = 0;
    for (int i = 0; i < 3; ++i) {
        const double x = exact_clamp(c[i] - lambda * n[i], lo[i], hi[i]);
        d2 += (x - c[i]) * (x - c[i]);
    }
    return d2;
}

/// True iff the closed disk {centre c, unit normal n, radius r} and the closed box [lo, hi] share a point.
/// Cheap decisions first, the exact closest-point problem only for the remaining cases:
///   centre in the box -> overlap;  plane misses the box -> none;
///   box farther than r from c (ball/box) -> none;  whole box within r of c and cut by the plane -> overlap.
PRT_HD inline bool disk_overlaps_box(const double c[3], const double n[3], double r, const double lo[3],
                                     const double hi[3]) {
    if (c[0] >= lo[0] && c[0] <= hi[0] && c[1] >= lo[1] && c[1] <= hi[1] && c[2] >= lo[2] && c[2] <= hi[2])
        return true;
    double g_max = 0, g_min = 0, near2 = 0, far2 = 0;
    for (int i = 0; i < 3; ++i) {
        const double a = lo[i] - c[i], b = hi[i] - c[i];
        g_max += exact_max(n[i] * a, n[i] * b);
        g_min += exact_min(n[i] * a, n[i] * b);
        const double near = a > 0 ? a : (b < 0 ? b : 0.0);
        near2 += near * near;
        far2 += exact_max(a * a, b * b);
    }
    const double r2 = r * r;
    if (g_min > 0 || g_max < 0 || near2 > r2) return false;
    if (far2 <= r2) return true;
    const double d2 = plane_box_distance_sq(c, n, lo, hi);
    return d2 >= 0 && d2 <= r2;
}

/// Half-extent of a disk's axis-aligned bounding box along axis i: r * sqrt(1 - n_i^2) (|n| = 1).
PRT_HD inline double disk_half_extent(double r, double n_i) {
    return r * sqrt(exact_max(0.0, 1.0 - n_i * n_i));
}

/// A point as the octree builder classifies it (thesis 3.1, 3.4): the disk (centre, radius, unit
/// normal rounded to float) and its bounding box rounded outward to float, so that rejecting a
/// child by the box is always safe. Made by make_build_splat, on the host (preprocess/splat/
/// octree_build.h) or on the GPU (runtime/cuda/src/octree_build.cu: the out-of-core build's cells).
struct BuildSplat {
    float c[3];
    float r;
    float n[3];  ///< unit (normalised in double, then rounded)
    std::uint32_t point;
    float box_lo[3];
    float box_hi[3];
};

/// thesis 3.1: whether point (p, n, r) can be a splat: a finite positive radius, a finite position
/// and a finite non-zero normal; `len` gets the normal's length (in double).
PRT_HD PRT_INLINE bool usable_build_point(const pool::Float3& p, const pool::Float3& n, float r,
                                          double& len) {
    len = sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
    const auto finite = [](float v) { return v - v == 0.0f; };  // false for NaN and +-Inf
    return r > 0 && finite(r) && finite(p.x) && finite(p.y) && finite(p.z) && len > 0 && len - len == 0.0;
}

/// The build record of a usable point (usable_build_point, whose `len` it takes): the unit normal
/// (normalised in double, then rounded) and the disk's bounding box, rounded outward.
PRT_HD PRT_INLINE BuildSplat make_build_splat(const pool::Float3& p, const pool::Float3& nrm, float r,
                                              double len, std::uint32_t point) {
    const double c[3] = {p.x, p.y, p.z};
    const double n[3] = {nrm.x / len, nrm.y / len, nrm.z / len};
    BuildSplat s{};
    for (int a = 0; a < 3; ++a) {
        s.c[a] = static_cast<float>(c[a]);
        s.n[a] = static_cast<float>(n[a]);
    }
    s.r = r;
    s.point = point;
    for (int a = 0; a < 3; ++a) {
        // the exact test uses the stored float normal: bound the box with it, renormalised
        const double na = double(s.n[a]);
        // + 1e-6 r: the stored normal is unit only to float precision; the box must stay a superset
        const double e = disk_half_extent(double(r), exact_min(1.0, fabs(na))) + 1e-6 * double(r);
        s.box_lo[a] = round_down(c[a] - e);
        s.box_hi[a] = round_up(c[a] + e);
    }
    return s;
}

/// The scale build_splat_morton_key takes for a root cube of edge `root_size` (2^21 - 1 cells per
/// edge), computed once per build.
PRT_HD PRT_INLINE double build_splat_morton_scale(float root_size) {
    return double(k_morton_max) / double(root_size);
}

/// The builders' order of their records (sort_by_morton on the CPU, the GPU's cells): the Morton
/// code of the centre's cell at 21 bits per axis of the root cube, `scale` from
/// build_splat_morton_scale, ties kept in input order by a stable sort.
PRT_HD PRT_INLINE std::uint64_t build_splat_morton_key(const float c[3], const float root_min[3],
                                                       double scale) {
    std::uint32_t q[3];
    for (int a = 0; a < 3; ++a)
        q[a] = static_cast<std::uint32_t>(
            exact_clamp((double(c[a]) - root_min[a]) * scale, 0.0, double(k_morton_max)));
    return morton3(q[0], q[1], q[2]);
}

/// The closed box of the octree node at `level` with integer cell coordinates `cell` (each <
/// 2^level) of the root cube (root_min, root_size): root_min + root_size * cell / 2^level in double
/// precision (preprocess/splat/octree_build.h, node_box).
PRT_HD PRT_INLINE void octree_node_box(const float root_min[3], float root_size, std::uint32_t level,
                                       const std::uint32_t cell[3], double lo[3], double hi[3]) {
    const double scale = double(root_size) / double(std::uint64_t(1) << level);
    for (int a = 0; a < 3; ++a) {
        lo[a] = double(root_min[a]) + scale * double(cell[a]);
        hi[a] = double(root_min[a]) + scale * double(std::uint64_t(cell[a]) + 1);
    }
}

/// Bit c of the result is set when the splat `s` belongs to child c of a node whose children's
/// closed boxes are child_lo / child_hi and whose mid-planes are `mid` (the lower children's upper
/// faces): replicating, the disk overlaps the child's closed box (thesis 3.4); otherwise the child
/// holding the centre (half-open cells: a centre on a mid-plane goes to the upper child). The disk
/// must overlap the node itself (the builder's invariant).
PRT_HD inline std::uint8_t disk_child_mask(const BuildSplat& s, bool replicate, const double mid[3],
                                           const double child_lo[8][3], const double child_hi[8][3]) {
    if (!replicate) {
        return static_cast<std::uint8_t>(1u << ((double(s.c[0]) >= mid[0] ? 1 : 0) |
                                                (double(s.c[1]) >= mid[1] ? 2 : 0) |
                                                (double(s.c[2]) >= mid[2] ? 4 : 0)));
    }
    // Per axis, which halves the disk's bounding box reaches (closed halves share the mid-plane).
    unsigned lower = 0, upper = 0;
    for (int a = 0; a < 3; ++a) {
        if (double(s.box_lo[a]) <= mid[a]) lower |= 1u << a;
        if (double(s.box_hi[a]) >= mid[a]) upper |= 1u << a;
    }
    const unsigned both = lower & upper;
    if (both == 0) {
        // One candidate child: the disk overlaps this node (invariant) and the node is the union
        // of its children, so the disk overlaps that child without an exact test.
        return static_cast<std::uint8_t>(1u << upper);
    }
    const double c[3] = {s.c[0], s.c[1], s.c[2]};
    const double n[3] = {s.n[0], s.n[1], s.n[2]};
    std::uint8_t mask = 0;
    for (unsigned child = 0; child < 8; ++child) {
        // candidate iff on every axis the child's half is reached by the bounding box
        bool candidate = true;
        for (int a = 0; a < 3 && candidate; ++a)
            candidate = (child >> a & 1u) ? (upper >> a & 1u) : (lower >> a & 1u);
        if (candidate && disk_overlaps_box(c, n, double(s.r), child_lo[child], child_hi[child]))
            mask |= static_cast<std::uint8_t>(1u << child);
    }
    return mask;
}

}  // namespace prt::core
