// PointRT core: ray tracing the exact MLS point-set surface of Wald & Seidel 2005 ("WS05"):
// Adamson and Alexa's implicit surface F(x) = W^2(x) f(x) = 0 (WS05 3.1.1, eq. 1-2), found per
// kd-tree cell by k regular samples (over the part of the cell's interval that the supports reach)
// and a sign change (WS05 3.2.1), with a kd-tree whose leaves reference every splat whose support
// overlaps them (WS05 3.4, built by prt-mls); rays reach the non-empty cells through a BVH over them
// where the pool has one (prt-mls since 2026-12-03; same cells, same hits: mls_walk_bvh).
// Host and device (PRT_HD): plain functions over an MlsView of the pool's sections; no allocation,
// recursion, exceptions or virtual calls. Every loop is bounded: the traversal stack by the
// validated tree depths (pool::k_max_mls_depth, k_max_mls_bvh_depth), the walk by MlsParams::max_steps,
// sampling by MlsParams::samples and refinement by MlsParams::refine_steps.
//
// Per ray, in the model's local frame (CPU loop or one CUDA thread per ray):
//     MlsHit hit; MlsStats stats;
//     if (trace_mls(view, o, d, t_max, inside, params, hit, stats)) ... hit.t, hit.position, hit.normal
//     bool shadowed = mls_occluded(view, o, d, t_max, inside, params, stats);
//     Vec3 srgb = mls_blend_color(view, colors, hit);   // optional: weighted point colors at the hit
// Host setup: prt::rt::load_mls_view(pool) (prt/runtime/surface_pools.h) validates the sections.
// Host code calling these in hot loops should build with -fno-math-errno: the four sample lanes
// of a cell (mls_sums_lanes) then vectorize with GCC (measured 1.45x fewer cycles per ray).
//
// The function (eq. 2): with w_i(x) = W(|x - p_i| / R_i), W(r) = max(0, 1 - r) (eq. 1's hat),
//     F(x) = (W(x) x - sum w_i p_i) . sum w_i n_i = (sum w_i (x - p_i)) . (sum w_i n_i)
// The second form is what this file evaluates: the same value, but each x - p_i is a short vector
// (|x - p_i| < R_i), so float sums do not cancel the model's position away (WS05's W x - P loses
// the bits of |x| to rounding; the MLS tests measure both forms against double precision).
// F > 0 on the side the normals point to (outside), F < 0 inside, F = 0 where no support reaches.
#pragma once

#include <cstdint>

#include "prt/core/config.h"
#include "prt/core/math.h"
#include "prt/formats/mls_layout.h"

namespace prt::core {

/// The MLS sections of one pool as the core reads them (built and validated on the host by
/// prt::rt::load_mls_view; the pointers may be device pointers to the same bytes).
struct MlsView {
    const pool::MlsNode* nodes = nullptr;    ///< node_count nodes, node 0 the root
    const std::uint32_t* refs = nullptr;     ///< ref_count splat indices, leaf after leaf
    const pool::MlsSplat* splats = nullptr;  ///< splat_count splats, local frame
    std::uint32_t node_count = 0;
    std::uint32_t ref_count = 0;
    std::uint32_t splat_count = 0;
    std::uint32_t depth = 0;  ///< deepest level (<= pool::k_max_mls_depth): bounds the stack
    Vec3 root_lo{0, 0, 0};    ///< root cell, local frame
    Vec3 root_hi{0, 0, 0};
    /// The BVH over the non-empty leaves (sections 52-53, optional): rays walk it instead of the
    /// kd-tree (same cells, same intervals, same hits; mls_walk_bvh). nullptr: the kd walk.
    const pool::MlsBvhNode* bvh_nodes = nullptr;
    const pool::MlsBvhLeaf* bvh_leaves = nullptr;
    std::uint32_t bvh_node_count = 0;
    std::uint32_t bvh_leaf_count = 0;
    std::uint32_t bvh_depth = 0;  ///< deepest BVH level (<= pool::k_max_mls_bvh_depth)
};

/// The view over MLS arrays (a pool's sections, validated by pool::validate_mls, or a model in
/// memory), counts and root cell from `info`. Host only.
inline MlsView make_mls_view(const pool::MlsInfo& info, const pool::MlsNode* nodes, const std::uint32_t* refs,
                             const pool::MlsSplat* splats) {
    MlsView view;
    view.nodes = nodes;
    view.refs = refs;
    view.splats = splats;
    view.node_count = info.node_count;
    view.ref_count = info.ref_count;
    view.splat_count = info.splat_count;
    view.depth = info.depth;
    view.root_lo = Vec3{info.root_lo[0], info.root_lo[1], info.root_lo[2]};
    view.root_hi = Vec3{info.root_hi[0], info.root_hi[1], info.root_hi[2]};
    return view;
}

/// Adds the BVH over the non-empty leaves to `view` (validated by pool::validate_mls, or built in
/// memory); nodes == nullptr or fewer than two leaves leaves the kd walk. Host only.
inline void attach_mls_bvh(MlsView& view, const pool::MlsBvhNode* nodes, const pool::MlsBvhLeaf* leaves,
                           std::uint32_t node_count, std::uint32_t leaf_count, std::uint32_t depth) {
    const bool use = nodes != nullptr && leaves != nullptr && leaf_count >= 2;
    view.bvh_nodes = use ? nodes : nullptr;
    view.bvh_leaves = use ? leaves : nullptr;
    view.bvh_node_count = use ? node_count : 0;
    view.bvh_leaf_count = use ? leaf_count : 0;
    view.bvh_depth = use ? depth : 0;
}

/// Which sign changes of F count as hits.
enum MlsFaces : std::uint32_t {
    /// Any sign change (the first root along the ray): the reference surface, primary rays.
    k_mls_faces_both = 0,
    /// thesis 3.6 seamless rule (prt/core/ray.h): outside rays accept only F going from + to -
    /// (entering, a front face), inside rays only - to + (leaving). Secondary and shadow rays
    /// leaving the surface then never re-hit the root they start on: no minimum hit distance.
    k_mls_faces_by_ray = 1,
};

/// Settings of the intersection (WS05 3.2).
struct MlsParams {
    /// WS05 3.2.1-3.2.2: regular samples per cell interval, both ends included (k; at least 2).
    /// WS05 uses 4 with a well-shrunk tree; MlsInfo::samples records what the tree was built for.
    std::uint32_t samples = 4;
    /// Regula falsi (Illinois) steps after the sign change, each one more evaluation of F; 0 is
    /// WS05's single linear interpolation between the two bracketing samples. One step removes
    /// the cell-shaped shading seams that interpolation leaves on coarse models (the kitten) for
    /// about 10-20% of the time (bench-mls.sh measures 0, 1 and 2).
    std::uint32_t refine_steps = 1;
    std::uint32_t faces = k_mls_faces_both;  ///< MlsFaces
    /// Sample only the part of a cell's interval where the ray meets the supports (the span from
    /// the first ball |x - p_i| < R_i it enters to the last it leaves; F = 0 elsewhere, so no root is
    /// lost), and skip the cell where it meets none. WS05 samples the whole cell: a thin sheet's
    /// band of supports (2 R thick) in a deep cell then falls between its k samples and the ray
    /// passes through the surface (a wall of prt-synth's room seen at a slant: half the rays).
    /// false: WS05's samples over the whole cell.
    bool clip_to_supports = true;
    /// More samples where a cell's span is long against the supports (with clip_to_supports; not in
    /// WS05): at least this many per R_min of ray length, R_min the smallest support radius the ray
    /// meets in the cell, up to max_samples. WS05's k over a long span lets the two roots of a thin
    /// part (both sides of an ear, a sheet scanned twice) fall between two samples: the ray passes
    /// through. Measured (prt-fidelity, 512^2, dev VM), holes of the decimated armadillo (10 %) 3.60 %
    /// -> 2.92 % (64 samples a cell: 2.58 %), of a kd-tree for the GPU (prt-mls defaults since
    /// 2026-12-03) 5.41 % -> 2.97 %; it costs the GPU 7 % on prt-synth's room and 23 % on a 1M
    /// sphere, whose cells hug the surface (H200, preprocess/mls/README.md). 0: k alone.
    float samples_per_support = 3.0f;
    std::uint32_t max_samples = 32;  ///< bound on the samples per cell samples_per_support asks (not on k)
    /// Nodes one ray may visit before the walk stops (MlsStats::truncated): a bound on every walk
    /// even for a corrupted view (a valid tree visits each node at most once per ray).
    std::uint32_t max_steps = 1u << 20;
};

/// Where a ray met the MLS surface.
struct MlsHit {
    float t = 0.0f;                ///< ray parameter (origin + t dir, t in [0, t_max))
    Vec3 position{0, 0, 0};        ///< local frame
    Vec3 normal{0, 0, 1};          ///< unit sum w_i n_i at the hit (WS05 3.2.1: "same loop"), outward
    std::uint32_t front = 0;       ///< 1 when F went from + to - (the ray entered: a front face)
    std::uint32_t point = 0;       ///< source point of the splat with the largest weight at the hit
    std::uint32_t leaf_first = 0;  ///< refs of the leaf holding the hit (for mls_blend_color)
    std::uint32_t leaf_count = 0;
};

/// Work counters of one query, WS05 4.3's per-ray statistics (sum them over rays).
struct MlsStats {
    std::uint32_t traversal_steps = 0;  ///< nodes visited, inner and leaf (kd-tree or BVH)
    std::uint32_t cells = 0;            ///< leaves visited (the kd walk's include empty ones)
    std::uint32_t intersections = 0;    ///< non-empty leaves whose interval was sampled
    std::uint32_t splats = 0;           ///< refs of those leaves ("splats visited")
    std::uint32_t evaluations = 0;      ///< evaluations of F (samples and refinement steps)
    std::uint32_t truncated = 0;        ///< walks stopped by max_steps or a full stack
};

/// The weighted sums at one point (WS05 eq. 2): F = dot(a, n).
template <class Real>
struct MlsSums {
    Real w = 0;                   ///< W(x) = sum w_i
    Real ax = 0, ay = 0, az = 0;  ///< sum w_i (x - p_i)
    Real nx = 0, ny = 0, nz = 0;  ///< sum w_i n_i
    Real w_max = 0;               ///< largest single weight (tracked only when asked)
    std::uint32_t heaviest = 0;   ///< MlsSplat::point of that splat
    PRT_HD PRT_INLINE Real f() const { return ax * nx + ay * ny + az * nz; }
};

namespace detail {

PRT_HD PRT_INLINE float mls_sqrt(float v) {
    return sqrtf(v);
}
PRT_HD PRT_INLINE double mls_sqrt(double v) {
    return sqrt(v);
}
PRT_HD PRT_INLINE float mls_abs(float v) {
    return fabsf(v);
}
PRT_HD PRT_INLINE double mls_abs(double v) {
    return fabs(v);
}

/// Reads a splat (load_32_bytes: two 16-byte read-only loads on the GPU).
PRT_HD PRT_INLINE pool::MlsSplat load_mls_splat(const pool::MlsSplat* p) {
    return load_32_bytes(p);
}

PRT_HD PRT_INLINE float mls_split_value(const pool::MlsNode& n) {
#if PRT_DEVICE_CODE
    return __uint_as_float(n.payload);
#else
    float f;
    static_assert(sizeof(f) == sizeof(n.payload));
    __builtin_memcpy(&f, &n.payload, sizeof(f));
    return f;
#endif
}

}  // namespace detail

/// Split position of an inner node.
PRT_HD PRT_INLINE float mls_node_split(const pool::MlsNode& n) {
    return detail::mls_split_value(n);
}

/// WS05 3.1.1, eq. 1-2: the weighted sums over refs[first, first + count) at x. Per splat
/// w = 1 - |x - p| / R for |x - p| < R, else 0. Real is the accumulation (and per-splat) precision:
/// float on the GPU, double for host references. `track` also records the heaviest splat.
template <class Real, bool track = false>
PRT_HD inline MlsSums<Real> mls_sums(const MlsView& v, std::uint32_t first, std::uint32_t count, Real x,
                                     Real y, Real z) {
    MlsSums<Real> s;
    const std::uint32_t end = first + count;
    for (std::uint32_t k = first; k < end; ++k) {
        const pool::MlsSplat sp = detail::load_mls_splat(v.splats + v.refs[k]);
        const Real dx = x - Real(sp.position.x);
        const Real dy = y - Real(sp.position.y);
        const Real dz = z - Real(sp.position.z);
        const Real inv = Real(sp.inv_support);
        const Real q = (dx * dx + dy * dy + dz * dz) * (inv * inv);
        if (!(q < Real(1))) continue;  // outside the support (also NaN)
        const Real w = Real(1) - detail::mls_sqrt(q);
        s.w += w;
        s.ax += w * dx;
        s.ay += w * dy;
        s.az += w * dz;
        s.nx += w * Real(sp.normal.x);
        s.ny += w * Real(sp.normal.y);
        s.nz += w * Real(sp.normal.z);
        if constexpr (track) {
            if (w > s.w_max) {
                s.w_max = w;
                s.heaviest = sp.point;
            }
        }
    }
    return s;
}

/// The leaf whose cell holds x (points on a split plane go left); returns its node index, or
/// node_count when x is outside the root cell or the walk is cut short.
PRT_HD inline std::uint32_t mls_locate_leaf(const MlsView& v, Vec3 x) {
    if (v.node_count == 0) return v.node_count;
    if (!(x.x >= v.root_lo.x && x.x <= v.root_hi.x && x.y >= v.root_lo.y && x.y <= v.root_hi.y &&
          x.z >= v.root_lo.z && x.z <= v.root_hi.z))
        return v.node_count;
    std::uint32_t node = 0;
    for (std::uint32_t level = 0; level <= pool::k_max_mls_depth; ++level) {  // bound: tree depth
        const pool::MlsNode n = v.nodes[node];
        if (pool::mls_node_is_leaf(n)) return node;
        const std::uint32_t axis = pool::mls_node_axis(n);
        node = pool::mls_node_left(n) + (component(x, static_cast<int>(axis)) <= mls_node_split(n) ? 0u : 1u);
        if (node >= v.node_count) return v.node_count;
    }
    return v.node_count;
}

/// F, W and the normal sum at x through the tree (the leaf holding x). Outside the root cell
/// every sum is 0.
template <class Real = float>
PRT_HD inline MlsSums<Real> mls_eval(const MlsView& v, Vec3 x) {
    const std::uint32_t leaf = mls_locate_leaf(v, x);
    if (leaf >= v.node_count) return MlsSums<Real>{};
    const pool::MlsNode n = v.nodes[leaf];
    return mls_sums<Real>(v, pool::mls_leaf_first(n), pool::mls_leaf_count(n), Real(x.x), Real(x.y),
                          Real(x.z));
}

namespace detail {

/// Fully unrolls a loop over the k_mls_lanes lanes (on the host too: GCC then keeps the lane
/// accumulators in registers and vectorizes them).
#if defined(__CUDACC__)
#define PRT_MLS_UNROLL_LANES _Pragma("unroll")
#elif defined(__clang__)
#define PRT_MLS_UNROLL_LANES _Pragma("clang loop unroll(full)")
#elif defined(__GNUC__)
#define PRT_MLS_UNROLL_LANES _Pragma("GCC unroll 4")
#else
#define PRT_MLS_UNROLL_LANES
#endif

/// Samples evaluated per sweep over a leaf's splats (WS05 3.2.2: "computing all four samples in a
/// single sweep"): each splat is loaded once for four points, and the four lanes are independent
/// (SIMD on the CPU, instruction-level parallelism on the GPU).
inline constexpr std::uint32_t k_mls_lanes = 4;

/// The weighted sums at k_mls_lanes points in one sweep over refs[first, first + count).
template <class Real>
struct MlsLanes {
    Real w[k_mls_lanes], ax[k_mls_lanes], ay[k_mls_lanes], az[k_mls_lanes];
    Real nx[k_mls_lanes], ny[k_mls_lanes], nz[k_mls_lanes];
};

template <class Real>
PRT_HD inline void mls_sums_lanes(const MlsView& v, std::uint32_t first, std::uint32_t count, const Real* xs,
                                  const Real* ys, const Real* zs, MlsLanes<Real>& out) {
    // Local accumulators (not `out`'s): they cannot alias the splat loads, so they stay in
    // registers and the four lanes vectorize.
    Real w[k_mls_lanes] = {}, ax[k_mls_lanes] = {}, ay[k_mls_lanes] = {}, az[k_mls_lanes] = {};
    Real sx[k_mls_lanes] = {}, sy[k_mls_lanes] = {}, sz[k_mls_lanes] = {};
    Real x[k_mls_lanes], y[k_mls_lanes], z[k_mls_lanes];
    PRT_MLS_UNROLL_LANES
    for (std::uint32_t l = 0; l < k_mls_lanes; ++l) {
        x[l] = xs[l];
        y[l] = ys[l];
        z[l] = zs[l];
    }
    const std::uint32_t end = first + count;
    for (std::uint32_t k = first; k < end; ++k) {
#if PRT_DEVICE_CODE
        const pool::MlsSplat sp = load_mls_splat(v.splats + v.refs[k]);
#else
        const pool::MlsSplat sp = v.splats[v.refs[k]];  // a plain copy: GCC's SLP vectorizer gives up
                                                        // on the same copy through a function
#endif
        const Real px = Real(sp.position.x), py = Real(sp.position.y), pz = Real(sp.position.z);
        const Real inv2 = Real(sp.inv_support) * Real(sp.inv_support);
        const Real nx = Real(sp.normal.x), ny = Real(sp.normal.y), nz = Real(sp.normal.z);
        PRT_MLS_UNROLL_LANES
        for (std::uint32_t l = 0; l < k_mls_lanes; ++l) {
            const Real dx = x[l] - px, dy = y[l] - py, dz = z[l] - pz;
            const Real q = (dx * dx + dy * dy + dz * dz) * inv2;
            // w = max(0, 1 - sqrt(q)) without a branch or select: (r + |r|) / 2 is r for r > 0
            // and 0 otherwise, exactly, so the lanes vectorize (with -fno-math-errno on the host)
            // and outside the support (q >= 1) the weight is 0 and adds nothing.
            const Real r = Real(1) - mls_sqrt(q);
            const Real wl = Real(0.5) * (r + mls_abs(r));
            w[l] += wl;
            ax[l] += wl * dx;
            ay[l] += wl * dy;
            az[l] += wl * dz;
            sx[l] += wl * nx;
            sy[l] += wl * ny;
            sz[l] += wl * nz;
        }
    }
    PRT_MLS_UNROLL_LANES
    for (std::uint32_t l = 0; l < k_mls_lanes; ++l) {
        out.w[l] = w[l];
        out.ax[l] = ax[l];
        out.ay[l] = ay[l];
        out.az[l] = az[l];
        out.nx[l] = sx[l];
        out.ny[l] = sy[l];
        out.nz[l] = sz[l];
    }
}

/// An accepted sign change of F between two neighbouring samples of one leaf (WS05 3.2.1), found by
/// mls_bracket_leaf during the walk and turned into a root by mls_finish_root after it.
template <class Real>
struct MlsBracket {
    float ta = 0.0f, tb = 0.0f;  ///< the bracketing samples' ray parameters (ta < tb)
    Real fa = 0, fb = 0;         ///< F there: opposite signs, fa != 0
    Vec3 n_sum{0, 0, 0};         ///< the sum of both samples' normal sums (fallback normal)
    std::uint32_t first = 0;     ///< refs of the leaf holding the bracket
    std::uint32_t count = 0;
    bool entering = false;  ///< F went from + to - (a front face)
};

/// Whether F going from fa to fb (in the ray's direction) is a crossing the face rule accepts;
/// `entering` tells which one (+ to -).
template <class Real>
PRT_HD PRT_INLINE bool mls_accepts(const MlsParams& p, bool inside, Real fa, Real fb, bool& entering) {
    entering = fa > Real(0) && fb <= Real(0);
    const bool leaving = fa < Real(0) && fb >= Real(0);
    return p.faces == k_mls_faces_by_ray ? (inside ? leaving : entering) : (entering || leaving);
}

/// The span [ca, cb] of [t0, t1] where the ray o + t d meets the support balls of refs[first,
/// first + count) (MlsParams::clip_to_supports), widened to the 64ths of [t0, t1] around it, and
/// the smallest support radius among the balls it meets (r_min); false when it meets none there.
/// The widening keeps the samples off the supports' edge, where W is a sliver and its sign, W > 0
/// or not, would rest on the last bits of the sums (which the CPU and the CUDA backend, built with
/// --use_fast_math, round differently).
PRT_HD inline bool mls_support_span(const MlsView& v, std::uint32_t first, std::uint32_t count, Vec3 o,
                                    Vec3 d, float t0, float t1, float& ca, float& cb, float& r_min) {
    const float inv_a = 1.0f / dot(d, d);
    float lo = k_inf, hi = -k_inf;
    r_min = k_inf;
    const std::uint32_t end = first + count;
    for (std::uint32_t k = first; k < end; ++k) {
        const pool::MlsSplat sp = load_mls_splat(v.splats + v.refs[k]);
        const Vec3 dx = o - vec3(sp.position);
        const float tc = -dot(dx, d) * inv_a;  // closest approach to p_i
        const Vec3 l = dx + d * tc;            // its offset from p_i, perpendicular to d
        const float r = 1.0f / sp.inv_support;
        const float h2 = (r * r - dot(l, l)) * inv_a;
        if (!(h2 > 0.0f)) continue;
        const float h = sqrtf(h2);
        r_min = fminf(r_min, r);
        lo = fminf(lo, tc - h);
        hi = fmaxf(hi, tc + h);
    }
    if (!(fmaxf(lo, t0) <= fminf(hi, t1))) return false;
    const float g = (t1 - t0) * (1.0f / 64.0f);
    ca = t0;
    cb = t1;
    if (g > 0.0f) {
        ca = fmaxf(t0, t0 + g * floorf((lo - t0) / g - 0.5f));
        cb = fminf(t1, t0 + g * ceilf((hi - t0) / g + 0.5f));
    }
    return true;
}

/// WS05 3.2.1 INTERSECT over one cell interval [t0, t1] of the ray, with the leaf's refs: k
/// regular samples (both ends included) over the part of it inside the supports
/// (MlsParams::clip_to_supports; k raised to MlsParams::samples_per_support per smallest support
/// radius met there), evaluated k_mls_lanes at a time, up to the first accepted sign change.
/// Returns true and fills `br` there; the root is interpolated by mls_finish_root.
template <class Real>
PRT_HD inline bool mls_bracket_leaf(const MlsView& v, std::uint32_t first, std::uint32_t count, Vec3 o,
                                    Vec3 d, float t0, float t1, bool inside, const MlsParams& p,
                                    MlsBracket<Real>& br, MlsStats& st) {
    float r_min = k_inf;
    if (p.clip_to_supports && !mls_support_span(v, first, count, o, d, t0, t1, t0, t1, r_min)) return false;
    std::uint32_t k = p.samples < 2u ? 2u : p.samples;
    if (p.samples_per_support > 0.0f && r_min < k_inf) {
        const float want = ceilf((t1 - t0) * sqrtf(dot(d, d)) * p.samples_per_support / r_min) + 1.0f;
        const float cap = static_cast<float>(p.max_samples);
        if (want > static_cast<float>(k) && cap > static_cast<float>(k))  // never fewer than k
            k = static_cast<std::uint32_t>(fminf(want, cap));
    }
    const float inv_k = 1.0f / static_cast<float>(k - 1u);
    bool prev_valid = false;
    Real prev_f = 0;
    float prev_t = t0;
    Vec3 prev_n{0, 0, 0};
    for (std::uint32_t base = 0; base < k; base += k_mls_lanes) {  // bound: k / 4 sweeps
        float ts[k_mls_lanes];
        Real xs[k_mls_lanes], ys[k_mls_lanes], zs[k_mls_lanes];
        PRT_UNROLL
        for (std::uint32_t l = 0; l < k_mls_lanes; ++l) {
            const std::uint32_t i = base + l < k ? base + l : k - 1u;  // spare lanes repeat the last sample
            // Both ends exactly (an unclipped t1 is shared with the next cell: no root falls
            // between cells).
            ts[l] = i + 1u == k ? t1 : t0 + (t1 - t0) * (static_cast<float>(i) * inv_k);
            const Vec3 x = o + d * ts[l];
            xs[l] = Real(x.x);
            ys[l] = Real(x.y);
            zs[l] = Real(x.z);
        }
        MlsLanes<Real> s;
        mls_sums_lanes<Real>(v, first, count, xs, ys, zs, s);
        const std::uint32_t lanes = k - base < k_mls_lanes ? k - base : k_mls_lanes;
        st.evaluations += lanes;
        for (std::uint32_t l = 0; l < lanes; ++l) {
            const float t = ts[l];
            if (!(s.w[l] > Real(0))) {  // no support here: f undefined, never interpolate across the gap
                prev_valid = false;
                continue;
            }
            const Real f = s.ax[l] * s.nx[l] + s.ay[l] * s.ny[l] + s.az[l] * s.nz[l];
            const Vec3 n_here = vec3(float(s.nx[l]), float(s.ny[l]), float(s.nz[l]));
            if (prev_valid) {
                bool entering = false;
                if (mls_accepts(p, inside, prev_f, f, entering)) {
                    br.ta = prev_t;
                    br.tb = t;
                    br.fa = prev_f;
                    br.fb = f;
                    br.n_sum = n_here + prev_n;
                    br.first = first;
                    br.count = count;
                    br.entering = entering;
                    return true;
                }
            }
            prev_valid = f != Real(0);
            prev_f = f;
            prev_t = t;
            prev_n = n_here;
        }
    }
    return false;
}

/// WS05 3.2.1: the root in a bracket by linear interpolation between its samples, refined by
/// MlsParams::refine_steps of regula falsi (Illinois variant: the bracket always holds the root).
/// Returns true when the root lies before t_max (and fills `hit` unless any_hit). A root at or
/// beyond t_max means a miss: every later accepted root along the ray lies beyond this bracket.
template <class Real, bool any_hit>
PRT_HD inline bool mls_finish_root(const MlsView& v, Vec3 o, Vec3 d, float t_max, const MlsParams& p,
                                   const MlsBracket<Real>& br, MlsHit* hit, MlsStats& st) {
    float ta = br.ta, tb = br.tb;
    Real fa = br.fa, fb = br.fb;
    int kept = 0;  // > 0: a kept that many times in a row, < 0: b
    for (std::uint32_t r = 0; r < p.refine_steps; ++r) {
        const float tm = ta + (tb - ta) * static_cast<float>(fa / (fa - fb));
        if (!(tm > ta && tm < tb)) break;  // converged to float resolution
        const Vec3 xm = o + d * tm;
        const MlsSums<Real> sm = mls_sums<Real>(v, br.first, br.count, Real(xm.x), Real(xm.y), Real(xm.z));
        ++st.evaluations;
        if (!(sm.w > Real(0))) break;
        const Real fm = sm.f();
        if (fm == Real(0)) {
            ta = tb = tm;
            fa = Real(1);
            fb = Real(-1);
            break;
        }
        if ((fm > Real(0)) == (fa > Real(0))) {
            ta = tm;
            fa = fm;
            if (kept > 0) fb *= Real(0.5);
            kept = kept > 0 ? kept + 1 : 1;
        } else {
            tb = tm;
            fb = fm;
            if (kept < 0) fa *= Real(0.5);
            kept = kept < 0 ? kept - 1 : -1;
        }
    }
    float th = ta + (tb - ta) * static_cast<float>(fa / (fa - fb));
    th = fminf(fmaxf(th, ta), tb);
    if (!(th < t_max)) return false;
    if constexpr (!any_hit) {
        // WS05 3.2.1: the normal from the same weighted sums, at the hit.
        const Vec3 xh = o + d * th;
        const MlsSums<Real> sh =
            mls_sums<Real, true>(v, br.first, br.count, Real(xh.x), Real(xh.y), Real(xh.z));
        ++st.evaluations;
        hit->t = th;
        hit->position = xh;
        hit->normal = normalize_or(vec3(float(sh.nx), float(sh.ny), float(sh.nz)),
                                   normalize_or(br.n_sum, -normalize(d)));
        hit->front = br.entering ? 1u : 0u;
        hit->point = sh.w > Real(0) ? sh.heaviest : 0u;
        hit->leaf_first = br.first;
        hit->leaf_count = br.count;
    }
    return true;
}

/// The slabs' bounds on the ray's interval in the box lo..hi, starting from [t0, t1] as given:
/// t = (plane - o) * inv_d per axis (inv_d[a] = 1 / d[a], 0 where d[a] = 0: that axis bounds nothing
/// where o lies in its slab, ends included, and misses elsewhere). False only for such a miss; the
/// caller compares t0 with t1.
PRT_HD PRT_INLINE bool mls_slab_range(const float* lo, const float* hi, Vec3 o, const float* inv_d, float& t0,
                                      float& t1) {
    PRT_UNROLL
    for (int a = 0; a < 3; ++a) {
        const float oa = component(o, a);
        if (inv_d[a] == 0.0f) {
            if (!(oa >= lo[a] && oa <= hi[a])) return false;
            continue;
        }
        float ta = (lo[a] - oa) * inv_d[a], tb = (hi[a] - oa) * inv_d[a];
        if (ta > tb) {
            const float s = ta;
            ta = tb;
            tb = s;
        }
        t0 = fmaxf(t0, ta);
        t1 = fminf(t1, tb);
    }
    return true;
}

/// The ray's interval [t0, t1] in the box lo..hi with t >= 0, as the kd walk crosses planes
/// (mls_slab_range). False on a miss.
PRT_HD PRT_INLINE bool mls_slab_interval(const float* lo, const float* hi, Vec3 o, const float* inv_d,
                                         float& t0, float& t1) {
    t0 = 0.0f;
    t1 = k_inf;
    return mls_slab_range(lo, hi, o, inv_d, t0, t1) && t0 <= t1;
}

/// Clips the ray to the root cell and fills inv_d (mls_slab_interval's). Not to t_max: each cell
/// is sampled over its whole interval, so a shadow ray (short t_max) takes the same samples as the
/// closest-hit ray along the same line and agrees with it; hits at t >= t_max are rejected, and
/// the walks never sample a cell starting at or beyond t_max. False on a miss, a NaN or a zero
/// direction.
PRT_HD PRT_INLINE bool mls_root_interval(const MlsView& v, Vec3 o, Vec3 d, float* inv_d, float& t0,
                                         float& t1) {
    PRT_UNROLL
    for (int a = 0; a < 3; ++a) {
        const float da = component(d, a);
        inv_d[a] = da == 0.0f ? 0.0f : 1.0f / da;
    }
    const float lo[3] = {v.root_lo.x, v.root_lo.y, v.root_lo.z},
                hi[3] = {v.root_hi.x, v.root_hi.y, v.root_hi.z};
    return mls_slab_interval(lo, hi, o, inv_d, t0, t1) && t1 < k_inf;
}

/// Front-to-back kd-tree walk (WS05 3.2, [Wal04]): each leaf is intersected over the ray interval
/// inside its cell, so the first accepted root is the closest. Split planes are crossed at
/// t = (split - o) / d, computed once per node, so the two children's intervals meet exactly: no
/// epsilon, and a ray lying in a plane or starting on it goes to the side it moves into.
/// While-while form (Aila and Laine 2009, "Understanding the efficiency of ray traversal on GPUs",
/// 3): each pass walks down to the next non-empty leaf (empty ones are popped on the way) and only
/// then samples it, and the bracket found is refined after the walk, so the rays of a GPU warp
/// sample their leaves and finish their roots together instead of one at a time.
template <class Real, bool any_hit>
PRT_HD inline bool mls_walk_kd(const MlsView& v, Vec3 o, Vec3 d, float t_max, bool inside, const MlsParams& p,
                               MlsHit* hit, MlsStats& st) {
    if (v.node_count == 0 || !(t_max > 0.0f)) return false;
    float t0 = 0.0f, t1 = k_inf;
    float inv_d[3];
    if (!mls_root_interval(v, o, d, inv_d, t0, t1)) return false;

    // A far child waiting: its interval starts where the near subtree's ends, which is the exit
    // of the last leaf visited before it is popped, so only t_far is stored (8 bytes an entry; one
    // entry per level at most, so the validated depth bounds the stack).
    struct Entry {
        std::uint32_t node;
        float t_far;
    };
    Entry stack[pool::k_max_mls_depth + 1];
    std::uint32_t sp = 0;
    std::uint32_t node = 0;
    float tn = t0, tf = t1;
    // The far child waiting on top of the stack, with its interval (the walk's one pop).
    auto pop = [&] {
        --sp;
        node = stack[sp].node;
        tn = tf;
        tf = stack[sp].t_far;
    };
    std::uint32_t step = 0;
    MlsBracket<Real> br;
    bool found = false;  // one exit from both loops: the warp reconverges before mls_finish_root
    for (bool walking = true; walking;) {  // one non-empty leaf a pass; bound: max_steps in all
        // Down to the next non-empty leaf (or the end of the walk).
        std::uint32_t first = 0, count = 0;
        for (;; ++step) {
            if (step >= p.max_steps || node >= v.node_count) {
                ++st.truncated;
                walking = false;
                break;
            }
            ++st.traversal_steps;
            const pool::MlsNode n = v.nodes[node];
            if (!(tn < t_max)) {  // every later cell starts at or beyond t_max (also NaN)
                walking = false;
                break;
            }
            if (pool::mls_node_is_leaf(n)) {
                ++st.cells;
                count = pool::mls_leaf_count(n);
                if (count > 0u) {
                    first = pool::mls_leaf_first(n);
                    ++step;
                    break;
                }
                if (sp == 0) {
                    walking = false;
                    break;
                }
                pop();
                continue;
            }
            const std::uint32_t axis = pool::mls_node_axis(n);
            const std::uint32_t left = pool::mls_node_left(n);
            const float split = mls_node_split(n);
            const float oa = component(o, static_cast<int>(axis));
            const float da = component(d, static_cast<int>(axis));
            const bool left_first = oa < split || (oa == split && da <= 0.0f);
            const std::uint32_t near_child = left_first ? left : left + 1u;
            const std::uint32_t far_child = left_first ? left + 1u : left;
            if (da == 0.0f) {  // parallel to the plane: one side only
                node = near_child;
                continue;
            }
            const float ts = (split - oa) * inv_d[axis];
            if (ts >= tf || ts <= 0.0f) {
                node = near_child;
            } else if (ts <= tn) {
                node = far_child;
            } else {
                if (sp > pool::k_max_mls_depth) {  // deeper than any valid tree: never for a valid view
                    ++st.truncated;
                    walking = false;
                    break;
                }
                stack[sp++] = Entry{far_child, tf};
                node = near_child;
                tf = ts;
            }
        }
        if (!walking) break;
        ++st.intersections;
        st.splats += count;
        if (mls_bracket_leaf<Real>(v, first, count, o, d, tn, tf, inside, p, br, st)) {
            found = true;
            break;
        }
        if (sp == 0) break;
        pop();
    }
    return found && mls_finish_root<Real, any_hit>(v, o, d, t_max, p, br, hit, st);
}

/// Whether the ray meets a BVH child's box before t_hi, and where it enters (t_near >= 0). inv_d as
/// mls_slab_range's; `parallel`: some component of d is 0 (such an axis bounds nothing where o
/// lies in the box's slab, faces included, and misses elsewhere). The exit is widened by 2^-21
/// relative (about 8 float ulps: Ize 2013's robust slab test) so rounding never skips a box the ray
/// grazes; the box only decides what is visited, never where a cell is sampled.
PRT_HD PRT_INLINE bool mls_bvh_box(const pool::MlsBvhChild& c, Vec3 o, const float* inv_d, bool parallel,
                                   float t_hi, float& t_near) {
    float tn = 0.0f, tf = t_hi;
    if (!parallel) {
        const float x0 = (c.lo[0] - o.x) * inv_d[0], x1 = (c.hi[0] - o.x) * inv_d[0];
        const float y0 = (c.lo[1] - o.y) * inv_d[1], y1 = (c.hi[1] - o.y) * inv_d[1];
        const float z0 = (c.lo[2] - o.z) * inv_d[2], z1 = (c.hi[2] - o.z) * inv_d[2];
        tn = fmaxf(fmaxf(fminf(x0, x1), fminf(y0, y1)), fmaxf(fminf(z0, z1), 0.0f));
        tf = fminf(fminf(fmaxf(x0, x1), fmaxf(y0, y1)), fminf(fmaxf(z0, z1), t_hi));
    } else if (!mls_slab_range(c.lo, c.hi, o, inv_d, tn, tf)) {
        return false;
    }
    t_near = tn;
    return tn <= tf * (1.0f + 1.0f / 2097152.0f);
}

/// Whether a ray parallel to an axis lies in the plane of the cell's lower bound on it, a split
/// plane: the kd walk sends such a ray to the lower cell (x[axis] <= split), so the BVH walk skips
/// this one (the two cells' samples could differ in the last bits).
PRT_HD PRT_INLINE bool mls_on_lower_split(const pool::MlsBvhLeaf& l, Vec3 o, const float* inv_d,
                                          Vec3 root_lo) {
    bool on = false;
    PRT_UNROLL
    for (int a = 0; a < 3; ++a)
        on = on || (inv_d[a] == 0.0f && component(o, a) == l.lo[a] && l.lo[a] != component(root_lo, a));
    return on;
}

/// The threads of the warp running this code together (GPU), 0 on the host.
PRT_HD PRT_INLINE unsigned mls_warp_mask() {
#if PRT_DEVICE_CODE
    return __activemask();
#else
    return 0u;
#endif
}

/// Whether `v` holds for any thread of `mask` (every one of them must call it: a warp vote on the
/// GPU); on the host the thread's own `v`.
PRT_HD PRT_INLINE bool mls_warp_any(unsigned mask, bool v) {
#if PRT_DEVICE_CODE
    return __any_sync(mask, v);
#else
    (void)mask;
    return v;
#endif
}

/// The kd walk's cells through the BVH over the non-empty leaves (MlsView::bvh_nodes): the same
/// leaves over the same intervals (each leaf's cell as the kd splits bound it, mls_slab_interval),
/// so the same first accepted root. Nearer child first; a leaf is sampled only where its cell
/// starts before t_max and before the best bracket found so far: cells are disjoint, so a cell
/// starting after that bracket's end holds no nearer root, and once every box left starts after it
/// the walk ends. Shadow rays (any_hit) stop at the first root before t_max in any order: the kd
/// walk's answer, since its first bracket is the nearest of all. While-while form (down to the next
/// leaf to sample, then sample it), and on the GPU the rays of a warp loop together until all are
/// done (a warp vote a pass), so they sample together. Counters: traversal_steps = BVH nodes and
/// leaves visited, cells = leaves visited.
template <class Real, bool any_hit>
PRT_HD inline bool mls_walk_bvh(const MlsView& v, Vec3 o, Vec3 d, float t_max, bool inside,
                                const MlsParams& p, MlsHit* hit, MlsStats& st) {
    if (v.node_count == 0 || !(t_max > 0.0f)) return false;
    float t0 = 0.0f, t1 = k_inf;
    float inv_d[3];
    if (!mls_root_interval(v, o, d, inv_d, t0, t1)) return false;  // the kd walk refuses the same rays
    const bool parallel = inv_d[0] == 0.0f || inv_d[1] == 0.0f || inv_d[2] == 0.0f;

    struct Entry {
        std::uint32_t ref;
        float t_near;
    };
    Entry stack[pool::k_max_mls_bvh_depth + 1];  // one waiting child per level
    std::uint32_t sp = 0;
    std::uint32_t ref = 0;  // node 0, the root
    bool have = true;       // `ref` is the next to visit
    float limit = t_max;    // boxes entered at or beyond it hold nothing to sample
    std::uint32_t step = 0;
    MlsBracket<Real> br, best;
    bool found = false;
    // The warp's rays that walk together (on the GPU): they sample together, one leaf each a pass,
    // until all are done (mls_warp_any). Without it the warp fell apart into groups sampling at
    // different times: 2.4-2.9 active threads a warp in the sums against the kd walk's 8.2, whose
    // walk ends at its first bracket (Nsight Compute, prt_mls_gpu_tests, H200).
    const unsigned warp = mls_warp_mask();
    bool done = false, occluded = false;
    for (;;) {
        // Down to the next leaf to sample (or the end of the walk): one pop, node or leaf a step, and
        // a leaf's cell checked here, so the rays of a GPU warp leave this loop only to sample.
        pool::MlsBvhLeaf l{};
        float c0 = 0.0f, c1 = 0.0f;
        int state = done ? 2 : 0;  // 0: searching, 1: at a leaf to sample, 2: the walk is over
        while (state == 0) {
            if (!have) {
                if (sp == 0) {
                    state = 2;
                } else {
                    --sp;
                    have = stack[sp].t_near <= limit;  // else it starts after the best bracket or t_max
                    ref = stack[sp].ref;
                }
            } else if (step >= p.max_steps) {
                ++st.truncated;
                state = 2;
            } else if (ref & pool::k_mls_bvh_leaf_bit) {
                ++step;
                ++st.traversal_steps;
                have = false;
                const std::uint32_t leaf = ref & ~pool::k_mls_bvh_leaf_bit;
                if (leaf >= v.bvh_leaf_count) {
                    ++st.truncated;
                    state = 2;
                } else {
                    ++st.cells;
                    l = load_32_bytes(v.bvh_leaves + leaf);
                    if (mls_slab_interval(l.lo, l.hi, o, inv_d, c0, c1) && c0 < c1 && c0 < t_max &&
                        (!found || c0 < best.tb) && !mls_on_lower_split(l, o, inv_d, v.root_lo))
                        state = 1;
                }
            } else if (ref >= v.bvh_node_count) {
                ++st.truncated;
                state = 2;
            } else {
                ++step;
                ++st.traversal_steps;
                const pool::MlsBvhChild ch0 = load_32_bytes(&v.bvh_nodes[ref].child[0]);
                const pool::MlsBvhChild ch1 = load_32_bytes(&v.bvh_nodes[ref].child[1]);
                float n0 = 0.0f, n1 = 0.0f;
                const bool h0 = mls_bvh_box(ch0, o, inv_d, parallel, limit, n0);
                const bool h1 = mls_bvh_box(ch1, o, inv_d, parallel, limit, n1);
                if (h0 && h1) {
                    if (sp > pool::k_max_mls_bvh_depth) {  // deeper than any valid tree
                        ++st.truncated;
                        state = 2;
                    } else {
                        const bool near0 = n0 <= n1;
                        stack[sp++] = Entry{near0 ? ch1.ref : ch0.ref, near0 ? n1 : n0};
                        ref = near0 ? ch0.ref : ch1.ref;
                    }
                } else if (h0 || h1) {
                    ref = h0 ? ch0.ref : ch1.ref;
                } else {
                    have = false;
                }
            }
        }
        if (state == 1) {
            ++st.intersections;
            st.splats += l.count;
            if (mls_bracket_leaf<Real>(v, l.first, l.count, o, d, c0, c1, inside, p, br, st)) {
                if constexpr (any_hit) {
                    // The root lies in [ta, tb] (mls_finish_root clamps it there).
                    if (br.tb < t_max || mls_finish_root<Real, true>(v, o, d, t_max, p, br, nullptr, st)) {
                        occluded = true;
                        done = true;
                    }
                } else if (!found || br.ta < best.ta) {
                    best = br;
                    found = true;
                    limit = fminf(limit, br.tb);
                }
            }
        } else {
            done = true;
        }
        if (!mls_warp_any(warp, !done)) break;
    }
    if constexpr (any_hit) {
        return occluded;
    } else {
        return found && mls_finish_root<Real, false>(v, o, d, t_max, p, best, hit, st);
    }
}

/// The ray walk: through the BVH where the view has one, else the kd-tree (same hits).
template <class Real, bool any_hit>
PRT_HD inline bool mls_walk(const MlsView& v, Vec3 o, Vec3 d, float t_max, bool inside, const MlsParams& p,
                            MlsHit* hit, MlsStats& st) {
    if (v.bvh_nodes != nullptr) return mls_walk_bvh<Real, any_hit>(v, o, d, t_max, inside, p, hit, st);
    return mls_walk_kd<Real, any_hit>(v, o, d, t_max, inside, p, hit, st);
}

}  // namespace detail

/// Closest root of F along o + t d with t in [0, t_max) (model local frame; d need not be unit).
/// Real: float (GPU, renderer) or double (host references). Returns false on a miss.
template <class Real = float>
PRT_HD inline bool trace_mls(const MlsView& v, Vec3 o, Vec3 d, float t_max, bool inside, const MlsParams& p,
                             MlsHit& hit, MlsStats& stats) {
    return detail::mls_walk<Real, false>(v, o, d, t_max, inside, p, &hit, stats);
}

/// Shadow rays: whether any accepted root lies in t in [0, t_max) (stops at the first one found).
template <class Real = float>
PRT_HD inline bool mls_occluded(const MlsView& v, Vec3 o, Vec3 d, float t_max, bool inside,
                                const MlsParams& p, MlsStats& stats) {
    return detail::mls_walk<Real, true>(v, o, d, t_max, inside, p, nullptr, stats);
}

/// Point colors blended with the MLS weights at the hit (display-encoded RGB in [0,1], as
/// stored); (1,1,1) without colors. Uses the refs of the leaf that held the hit.
PRT_HD inline Vec3 mls_blend_color(const MlsView& v, const pool::Rgba8* colors, const MlsHit& hit) {
    if (colors == nullptr) return Vec3{1.0f, 1.0f, 1.0f};
    float wsum = 0.0f;
    Vec3 c{0, 0, 0};
    const std::uint32_t end = hit.leaf_first + hit.leaf_count;
    for (std::uint32_t k = hit.leaf_first; k < end; ++k) {
        const pool::MlsSplat sp = detail::load_mls_splat(v.splats + v.refs[k]);
        const Vec3 dx = hit.position - vec3(sp.position);
        const float q = length2(dx) * sp.inv_support * sp.inv_support;
        if (!(q < 1.0f)) continue;
        const float w = 1.0f - sqrtf(q);
        const pool::Rgba8 col = colors[sp.point];
        c += Vec3{float(col.r), float(col.g), float(col.b)} * w;
        wsum += w;
    }
    if (!(wsum > 0.0f)) {
        const pool::Rgba8 col = colors[hit.point];
        return Vec3{float(col.r), float(col.g), float(col.b)} * (1.0f / 255.0f);
    }
    return c * (1.0f / (255.0f * wsum));
}

}  // namespace prt::core
