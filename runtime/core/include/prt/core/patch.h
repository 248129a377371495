// PointRT core: ray tracing bicubic Bezier patches through the mixed hierarchy of seed 002
// (a BVH over patches, a fixed-depth subpatch tree under each, Newton iteration in double
// precision from the chosen subpatch's centre). Host and device (PRT_HD): plain functions over a
// PatchView of the pool's sections; no allocation, recursion, exceptions or virtual calls. Every
// loop is bounded: traversal stacks by the validated tree depths, Newton by max_iterations.
//
// Per ray (CPU, seed 002, 5.4; also usable one thread per ray in a kernel):
//     PatchRay ray = make_patch_ray(origin_local, dir_local, t_max, inside);
//     PatchHit hit;
//     if (trace_patches(view, ray, params, hit)) ... hit.t, hit.position, hit.normal, hit.front
//     bool shadowed = patches_occluded(view, shadow_ray, params);
//     trace_patches<PatchPrecision::f32>(...): Newton in float (the suite's trade; not the renderer's)
// Data-parallel split of seed 002, 5.3 (traverse / recheck + newton kernels):
//     patch_bvh_candidates() per ray -> (ray, patch) pairs -> intersect_patch() per pair.
// Back-face culling per view (5.2), oriented pools only (PatchInfo::flags & k_patch_oriented):
//     mark_backfacing_patch() per patch, then mark_backfacing_bvh(), once per eye position.
// Beyond the paper: leaves along a collapsed patch edge (the teapot's lid top and bottom centre)
// fall back to patch_apex_newton(), where Newton from the leaf centre loses the polar angle.
#pragma once

#include <cstddef>
#include <cstdint>

#include "prt/core/bezier.h"
#include "prt/core/config.h"
#include "prt/core/math.h"
#include "prt/formats/patch_layout.h"

namespace prt::core {

/// The patch sections of one pool as the core reads them (built and validated on the host by
/// prt::rt::load_patch_view; the pointers may be device pointers to the same bytes).
struct PatchView {
    const pool::PatchControlNet* nets = nullptr;  ///< patch_count nets, local frame
    const pool::PatchBvhNode* bvh = nullptr;      ///< bvh_node_count nodes, depth first with skips
    const pool::SubpatchNode* nodes = nullptr;    ///< patch_count * subpatch_nodes, per patch level order
    std::uint32_t patch_count = 0;
    std::uint32_t bvh_node_count = 0;
    std::uint32_t subpatch_depth = 0;  ///< leaves are at this level of every subpatch tree
    std::uint32_t subpatch_nodes = 1;  ///< 2^(subpatch_depth + 1) - 1
    std::uint32_t flags = 0;           ///< pool::PatchFlags
    double extent = 1.0;               ///< largest side of the model's box: scales the tolerances
};

/// Marks "no patch" (PatchHit::patch of a miss, PatchTraceParams::skip_patch unused).
inline constexpr std::uint32_t k_no_patch = 0xffffffffu;

/// A ray in the model's local frame, in double precision. `dir` need not be unit length: t is the
/// ray parameter (origin + t * dir), so it is the same in every frame (see prt/core/ray.h).
struct PatchRay {
    DVec3 origin;
    DVec3 dir;
    double t_max;          ///< hits at t >= t_max are ignored (a light's distance for shadow rays)
    std::uint32_t inside;  ///< thesis 3.6 seamless flag (RayFlags k_ray_inside): expects back faces
};

/// A PatchRay from the core's float ray fields (Ray::origin, dir, t_max, ray_inside()).
PRT_HD PRT_INLINE PatchRay make_patch_ray(Vec3 origin, Vec3 dir, float t_max, bool inside) {
    return PatchRay{dvec3(origin), dvec3(dir), static_cast<double>(t_max), inside ? 1u : 0u};
}

/// Which faces a hit may be on.
enum PatchFaces : std::uint32_t {
    /// Both faces (default): the data's u/v orientation is not consistent, shade two-sided.
    k_patch_faces_both = 0,
    /// The seamless rule of prt/core/ray.h: outside rays keep front faces (dot(dir, n) < 0), inside
    /// rays back faces. Meaningful only for oriented pools (k_patch_oriented); replaces any minimum
    /// hit distance for secondary rays.
    k_patch_faces_by_ray = 1,
};

/// Settings of the intersection (seed 002, 3 and 6).
struct PatchTraceParams {
    std::uint32_t max_iterations = 16;  ///< seed 002, 3: at most 16 Newton steps
    /// Convergence: both plane residuals |n_i . Q + d_i| <= tolerance * PatchView::extent (seed 002
    /// uses 1e-15 absolute on models ~3 units across; relative here so any scale works).
    double tolerance = 1e-12;
    /// Newton iterates outside [-margin, 1 + margin]^2 have left the patch: no hit from that start.
    double domain_margin = 0.25;
    /// Roots within [-edge_tolerance, 1 + edge_tolerance]^2 are hits (clamped into [0,1]^2), so a
    /// ray through a shared edge is not lost to rounding on both patches (no cracks).
    double edge_tolerance = 1e-7;
    /// The residual growing this many steps in a row means divergence (seed 002, 3).
    std::uint32_t max_residual_increases = 3;
    /// Stagnation: this many steps in a row without halving the smallest residual so far also end
    /// the run as diverged (0: off). From a subpatch leaf's centre Newton converges quadratically,
    /// or it cycles without converging (seed 002's "starts to diverge" in another form): such runs
    /// would otherwise take all max_iterations steps (16% of the steps on the teapot).
    std::uint32_t max_stalled_steps = 4;
    /// A run whose iterate comes within this distance (parameter space, max norm) of the root
    /// already accepted on the same patch for this ray stops there (NewtonStatus::known_root): it
    /// converges to that root, which cannot make the hit nearer. Neighbouring leaves overlap, and
    /// their runs mostly find the same root (0: off).
    double duplicate_radius = 1e-4;
    std::uint32_t faces = k_patch_faces_both;  ///< PatchFaces
    /// Self-intersection guard for secondary rays on unoriented pools: roots on patch skip_patch
    /// within skip_radius (parameter space, max norm) of (skip_u, skip_v) are ignored.
    std::uint32_t skip_patch = k_no_patch;
    double skip_u = 0.0, skip_v = 0.0;
    double skip_radius = 1e-6;
};

/// Where and how a ray met a patch.
struct PatchHit {
    double t = 0.0;           ///< ray parameter
    double u = 0.0, v = 0.0;  ///< patch parameters of the hit, in [0,1]^2
    std::uint32_t patch = k_no_patch;
    std::uint32_t front = 0;  ///< 1 when dot(dir, normal) < 0 (the ray sees dQ/du x dQ/dv's side)
    DVec3 position{0, 0, 0};  ///< Q(u, v), local frame
    DVec3 normal{0, 0, 1};  ///< unit dQ/du x dQ/dv (exact, seed 002, 3); flip when !front to shade two-sided
    std::uint32_t iterations = 0;  ///< Newton steps of the accepted root
};

/// Work counters of one query (per ray; sum them for statistics).
struct PatchStats {
    std::uint32_t bvh_nodes = 0;       ///< BVH boxes tested
    std::uint32_t patches = 0;         ///< patches whose subpatch tree was entered
    std::uint32_t subpatch_boxes = 0;  ///< subpatch boxes tested
    std::uint32_t newton_runs = 0;     ///< Newton iterations started (one per candidate leaf, + apex solves)
    std::uint32_t newton_iterations = 0;  ///< Newton steps, all runs
};

/// Back-face culling bits (seed 002, 5.2) for one eye position: a set bit culls that node.
/// node_words: patch_cull_words(view) words per patch, bit k = subpatch node k;
/// bvh_words: bit i = BVH node i. Built by mark_backfacing_patch / mark_backfacing_bvh.
struct PatchCullMask {
    const std::uint32_t* node_words = nullptr;
    const std::uint32_t* bvh_words = nullptr;
};

// ---- Ray as two planes (seed 002, 3 and 5.2) ------------------------------------------------------

/// The ray as the intersection of two planes n1.x + d1 = 0 and n2.x + d2 = 0 (unit, orthogonal).
struct RayPlanes {
    DVec3 n1;
    double d1;
    DVec3 n2;
    double d2;
};

/// seed 002, 5.2: n1 = e_k x dir for the axis k of dir's smallest component, n2 = dir x n1.
PRT_HD inline RayPlanes make_ray_planes(DVec3 origin, DVec3 dir) {
    const double ax = fabs(dir.x), ay = fabs(dir.y), az = fabs(dir.z);
    const DVec3 e = (ax <= ay && ax <= az) ? DVec3{1, 0, 0} : (ay <= az ? DVec3{0, 1, 0} : DVec3{0, 0, 1});
    DVec3 n1 = cross(e, dir);
    n1 = n1 * (1.0 / length(n1));
    DVec3 n2 = cross(dir, n1);
    n2 = n2 * (1.0 / length(n2));
    return RayPlanes{n1, -dot(n1, origin), n2, -dot(n2, origin)};
}

// ---- Newton iteration (seed 002, eq. 2-4) ---------------------------------------------------------

enum class NewtonStatus : std::uint32_t {
    converged = 0,       ///< residual below the tolerance (the root may still lie outside [0,1]^2)
    no_convergence = 1,  ///< max_iterations reached
    diverged = 2,        ///< residual kept growing, or became NaN
    left_domain = 3,     ///< an iterate left [-margin, 1 + margin]^2
    singular = 4,        ///< the Jacobian cannot be inverted (ray parallel to the surface there)
    known_root = 5,      ///< the iterate reached the known root (PatchTraceParams::duplicate_radius)
};

struct NewtonResult {
    double u, v;
    std::uint32_t iterations;  ///< Newton steps taken
    NewtonStatus status;
};

/// The stopping rules Newton's runs share (patch_newton, patch_newton_f32), seed 002, 3.
struct NewtonTrack {
    double previous = 0.0, smallest = 0.0;
    std::uint32_t increases = 0, stalled = 0;

    /// After the convergence test of step `it` with residual `err`: true when the run diverges
    /// (the residual grew max_residual_increases steps in a row, or stagnated: max_stalled_steps
    /// steps without halving its smallest value).
    PRT_HD PRT_INLINE bool diverging(double err, std::uint32_t it, const PatchTraceParams& params) {
        if (it > 0 && err > previous) {
            if (++increases >= params.max_residual_increases) return true;
        } else {
            increases = 0;
        }
        if (it == 0 || err < 0.5 * smallest) {
            smallest = err;
            stalled = 0;
        } else if (params.max_stalled_steps > 0 && ++stalled >= params.max_stalled_steps) {
            return true;
        }
        previous = err;
        return false;
    }
};

/// After the update of step `it` to (u, v): true (with r's status set) when the iterate left
/// [-margin, 1 + margin]^2 (NaN too) or came within known_radius of the known root.
PRT_HD PRT_INLINE bool newton_stops_at(double u, double v, std::uint32_t it, const PatchTraceParams& params,
                                       double known_u, double known_v, double known_radius, NewtonResult& r) {
    const double lo = -params.domain_margin, hi = 1.0 + params.domain_margin;
    NewtonStatus status;
    if (!(u >= lo && u <= hi && v >= lo && v <= hi))
        status = NewtonStatus::left_domain;
    else if (fabs(u - known_u) < known_radius && fabs(v - known_v) < known_radius)
        status = NewtonStatus::known_root;
    else
        return false;
    r.u = u;
    r.v = v;
    r.iterations = it + 1;
    r.status = status;
    return true;
}

/// seed 002, eq. 3-4: (u, v) <- (u, v) - J^-1 R(u, v), R = (n1.Q + d1, n2.Q + d2), from (u0, v0),
/// in double precision. `tolerance` is absolute (local units). With known_radius > 0 an iterate
/// within known_radius of (known_u, known_v) ends the run (NewtonStatus::known_root).
PRT_HD inline NewtonResult patch_newton(const pool::PatchControlNet& net, const RayPlanes& planes, double u0,
                                        double v0, const PatchTraceParams& params, double tolerance,
                                        double known_u = 0.0, double known_v = 0.0, double known_radius = 0.0) {
    NewtonResult r{u0, v0, 0, NewtonStatus::no_convergence};
    double u = u0, v = v0;
    NewtonTrack track;
    for (std::uint32_t it = 0;; ++it) {
        const PatchEval e = patch_eval(net, u, v);
        const double r1 = dot(planes.n1, e.q) + planes.d1;
        const double r2 = dot(planes.n2, e.q) + planes.d2;
        const double err = dmax(fabs(r1), fabs(r2));  // NaN: caught just below (err == err)
        r.u = u;
        r.v = v;
        r.iterations = it;
        if (!(err == err)) {
            r.status = NewtonStatus::diverged;
            return r;
        }
        if (err <= tolerance) {
            r.status = NewtonStatus::converged;
            return r;
        }
        if (it >= params.max_iterations) {
            r.status = NewtonStatus::no_convergence;
            return r;
        }
        if (track.diverging(err, it, params)) {
            r.status = NewtonStatus::diverged;
            return r;
        }
        const double j11 = dot(planes.n1, e.qu), j12 = dot(planes.n1, e.qv);
        const double j21 = dot(planes.n2, e.qu), j22 = dot(planes.n2, e.qv);
        const double det = j11 * j22 - j12 * j21;
        // Relative to the terms it is made of: a determinant lost to cancellation is singular.
        if (!(fabs(det) > 1e-14 * (fabs(j11 * j22) + fabs(j12 * j21)))) {
            r.status = NewtonStatus::singular;
            return r;
        }
        const double inv = 1.0 / det;
        u -= (j22 * r1 - j12 * r2) * inv;
        v -= (j11 * r2 - j21 * r1) * inv;
        if (newton_stops_at(u, v, it, params, known_u, known_v, known_radius, r)) return r;
    }
}

/// Which arithmetic Newton runs in (issue 9's float-versus-double trade). The renderer (CPU and
/// CUDA backends) uses f64, as seed 002, 5.3.3 does; f32 is for measuring what double buys.
enum class PatchPrecision : std::uint32_t { f64 = 0, f32 = 1 };

/// patch_newton in single precision: the planes, Q and its derivatives (patch_eval_f32), the
/// residuals and the Jacobian in float, with the same stopping rules. A float residual cannot fall
/// below the rounding of the terms it is made of, so convergence is |r_i| <= max(tolerance,
/// 16 eps_f (|Q|_1 + |d_i|)): far from the origin that floor, not `tolerance`, is the accuracy.
/// The root (u, v) is returned in double, for accept_root's double evaluation of the hit.
PRT_HD inline NewtonResult patch_newton_f32(const pool::PatchControlNet& net, const RayPlanes& planes, double u0,
                                            double v0, const PatchTraceParams& params, double tolerance,
                                            double known_u = 0.0, double known_v = 0.0, double known_radius = 0.0) {
    constexpr float k_eps = 1.1920929e-7f;  // FLT_EPSILON
    const Vec3 n1 = to_vec3(planes.n1), n2 = to_vec3(planes.n2);
    const float d1 = static_cast<float>(planes.d1), d2 = static_cast<float>(planes.d2);
    const float tol = static_cast<float>(tolerance);
    NewtonResult r{u0, v0, 0, NewtonStatus::no_convergence};
    float u = static_cast<float>(u0), v = static_cast<float>(v0);
    NewtonTrack track;
    for (std::uint32_t it = 0;; ++it) {
        const PatchEvalF e = patch_eval_f32(net, u, v);
        const float p1 = dot(n1, e.q), p2 = dot(n2, e.q);
        const float r1 = p1 + d1, r2 = p2 + d2;
        r.u = u;
        r.v = v;
        r.iterations = it;
        if (!(r1 == r1 && r2 == r2)) {
            r.status = NewtonStatus::diverged;
            return r;
        }
        // rounding of Q's Bernstein sums and of the dot products: relative to |Q|, not to n . Q
        const float q1 = fabsf(e.q.x) + fabsf(e.q.y) + fabsf(e.q.z);
        const float floor1 = 16.0f * k_eps * (q1 + fabsf(d1)), floor2 = 16.0f * k_eps * (q1 + fabsf(d2));
        if (fabsf(r1) <= (tol > floor1 ? tol : floor1) && fabsf(r2) <= (tol > floor2 ? tol : floor2)) {
            r.status = NewtonStatus::converged;
            return r;
        }
        if (it >= params.max_iterations) {
            r.status = NewtonStatus::no_convergence;
            return r;
        }
        if (track.diverging(fabsf(r1) > fabsf(r2) ? fabsf(r1) : fabsf(r2), it, params)) {
            r.status = NewtonStatus::diverged;
            return r;
        }
        const float j11 = dot(n1, e.qu), j12 = dot(n1, e.qv);
        const float j21 = dot(n2, e.qu), j22 = dot(n2, e.qv);
        const float det = j11 * j22 - j12 * j21;
        if (!(fabsf(det) > 1e-6f * (fabsf(j11 * j22) + fabsf(j12 * j21)))) {
            r.status = NewtonStatus::singular;
            return r;
        }
        const float inv = 1.0f / det;
        u -= (j22 * r1 - j12 * r2) * inv;
        v -= (j11 * r2 - j21 * r1) * inv;
        if (newton_stops_at(u, v, it, params, known_u, known_v, known_radius, r)) return r;
    }
}

// ---- Boxes (single precision, seed 002, 6) --------------------------------------------------------

/// A ray prepared for slab tests in float.
struct BoxRay {
    float ox, oy, oz;
    float ix, iy, iz;  ///< 1 / dir, with |dir| components below 1e-30 raised to +-1e-30 (no 0 * inf NaN)
};

/// 1 / d for the slab test: finite for every d (a zero component becomes +-1e30).
PRT_HD PRT_INLINE float safe_inverse(double d) {
    const double a = fabs(d) < 1e-30 ? (d < 0.0 ? -1e-30 : 1e-30) : d;
    return static_cast<float>(1.0 / a);
}

PRT_HD PRT_INLINE BoxRay make_box_ray(const PatchRay& r) {
    return BoxRay{static_cast<float>(r.origin.x), static_cast<float>(r.origin.y),
                  static_cast<float>(r.origin.z), safe_inverse(r.dir.x),
                  safe_inverse(r.dir.y),          safe_inverse(r.dir.z)};
}

// Plain comparisons (minss / maxss; fminf is a library call on the host without -ffast-math).
// Slab distances are never NaN (safe_inverse), so NaN semantics do not matter here.
PRT_HD PRT_INLINE float min_f(float a, float b) {
    return a < b ? a : b;
}
PRT_HD PRT_INLINE float max_f(float a, float b) {
    return a > b ? a : b;
}

/// Slab test against [lo, hi] for t in [0, t_limit]; t_near = entry parameter (0 when inside).
/// The far distance is scaled by 1 + 2 gamma(3) so rounding never loses a hit (Ize 2013).
PRT_HD PRT_INLINE bool box_hit(const BoxRay& r, const float* lo, const float* hi, float t_limit,
                               float& t_near) {
    const float tx0 = (lo[0] - r.ox) * r.ix, tx1 = (hi[0] - r.ox) * r.ix;
    const float ty0 = (lo[1] - r.oy) * r.iy, ty1 = (hi[1] - r.oy) * r.iy;
    const float tz0 = (lo[2] - r.oz) * r.iz, tz1 = (hi[2] - r.oz) * r.iz;
    const float t0 = max_f(max_f(min_f(tx0, tx1), min_f(ty0, ty1)), max_f(min_f(tz0, tz1), 0.0f));
    const float t1 = min_f(min_f(max_f(tx0, tx1), max_f(ty0, ty1)), max_f(tz0, tz1)) * 1.00000036f;
    t_near = t0;
    return t0 <= t1 && t0 <= t_limit;
}

// ---- One (ray, patch) pair: subpatch tree + Newton (seed 002, 5.3.2-5.3.3, 5.4) --------------------

/// Per-ray state shared by the per-patch steps: planes, box ray, the nearest hit so far.
struct PatchQuery {
    PatchRay ray;
    RayPlanes planes;
    BoxRay box;
    double tolerance;   ///< absolute Newton tolerance (params.tolerance * view.extent)
    double best_t;      ///< nearest accepted hit so far (ray.t_max initially)
    std::uint32_t any;  ///< stop at the first accepted hit (shadow rays)
    std::uint32_t best_patch;  ///< patch of the last accepted root (k_no_patch: none yet)
    double best_u, best_v;     ///< its parameters (PatchTraceParams::duplicate_radius)
};

/// Prepares a query; false for a ray whose direction is zero or not finite (it hits nothing).
PRT_HD PRT_INLINE bool make_patch_query(const PatchView& view, const PatchRay& ray,
                                        const PatchTraceParams& params, bool any_hit, PatchQuery& q) {
    const double l2 = dot(ray.dir, ray.dir);
    if (!(l2 > 0.0) || !is_finite(ray.dir) || !is_finite(ray.origin) || !(ray.t_max > 0.0)) return false;
    q.ray = ray;
    q.planes = make_ray_planes(ray.origin, ray.dir);
    q.box = make_box_ray(ray);
    q.tolerance = params.tolerance * view.extent;
    q.best_t = ray.t_max;
    q.best_patch = k_no_patch;
    q.best_u = q.best_v = 0.0;
    q.any = any_hit ? 1u : 0u;
    return true;
}

/// Whether culling bit `bit` is set in `words`.
PRT_HD PRT_INLINE bool cull_bit(const std::uint32_t* words, std::size_t bit) {
    return (words[bit >> 5] >> (bit & 31u)) & 1u;
}

/// Words of culling bits per patch (bits for its subpatch_nodes nodes, rounded up to whole words so
/// patches never share a word: one thread per patch may write them without atomics).
PRT_HD PRT_INLINE std::uint32_t patch_cull_words(const PatchView& view) {
    return (view.subpatch_nodes + 31u) / 32u;
}
/// Words of culling bits for the BVH.
PRT_HD PRT_INLINE std::uint32_t bvh_cull_words(const PatchView& view) {
    return (view.bvh_node_count + 31u) / 32u;
}

/// The unit normal of a root (patch_normal with the ray's reverse as the fallback). Out of line on
/// the device: the traversal loop calls it only for oriented pools, and once per ray at the end.
/// Out-of-line functions take values, never the caller's query or hit by reference: an address
/// passed to a call would keep those in local memory throughout the traversal loop.
PRT_HD PRT_NOINLINE inline DVec3 root_normal(const pool::PatchControlNet& net, double u, double v, PatchEval ev,
                                             DVec3 dir) {
    return patch_normal(net, u, v, ev, dir * (-1.0 / length(dir)));
}

/// Accepts a Newton result as a hit if it converged inside the patch (within edge_tolerance), is
/// not the skipped start point, lies in (0, q.best_t) and faces the right way; then updates
/// q.best_t and the hit's t, u, v, patch and iterations (and front for k_patch_faces_by_ray).
/// position, normal and front are left to finish_patch_hit(), once per ray after the traversal:
/// the traversal loop then keeps neither them nor patch_normal's code in registers.
PRT_HD inline bool accept_root(const PatchView& view, std::uint32_t patch, const NewtonResult& nr,
                               PatchQuery& q, const PatchTraceParams& params, PatchHit& hit) {
    if (nr.status != NewtonStatus::converged) return false;
    const double e = params.edge_tolerance;
    if (!(nr.u >= -e && nr.u <= 1.0 + e && nr.v >= -e && nr.v <= 1.0 + e)) return false;
    const double u = dmin(dmax(nr.u, 0.0), 1.0), v = dmin(dmax(nr.v, 0.0), 1.0);
    if (patch == params.skip_patch && fabs(u - params.skip_u) <= params.skip_radius &&
        fabs(v - params.skip_v) <= params.skip_radius)
        return false;
    const pool::PatchControlNet& net = view.nets[patch];
    const PatchEval ev = patch_eval(net, u, v);
    const double t = dot(ev.q - q.ray.origin, q.ray.dir) / dot(q.ray.dir, q.ray.dir);
    if (!(t > 0.0 && t < q.best_t)) return false;
    if (params.faces == k_patch_faces_by_ray) {
        const double dn = dot(q.ray.dir, root_normal(net, u, v, ev, q.ray.dir));
        if (!(q.ray.inside ? dn > 0.0 : dn < 0.0)) return false;
        hit.front = dn < 0.0 ? 1u : 0u;
    }
    q.best_t = t;
    q.best_patch = patch;
    q.best_u = u;
    q.best_v = v;
    hit.t = t;
    hit.u = u;
    hit.v = v;
    hit.patch = patch;
    hit.iterations = nr.iterations;
    return true;
}

/// Completes a hit recorded by accept_root: position Q(u, v), the unit normal and the face, the
/// same values accept_root computed for its tests (same evaluation, same (u, v)).
PRT_HD inline void finish_patch_hit(const PatchView& view, const PatchQuery& q, PatchHit& hit) {
    const pool::PatchControlNet& net = view.nets[hit.patch];
    const PatchEval ev = patch_eval(net, hit.u, hit.v);
    hit.position = ev.q;
    hit.normal = root_normal(net, hit.u, hit.v, ev, q.ray.dir);
    hit.front = dot(q.ray.dir, hit.normal) < 0.0 ? 1u : 0u;
}

/// Collapsed edges of a net (all four control points equal): bit 0 u = 0, bit 1 u = 1,
/// bit 2 v = 0, bit 3 v = 1. The teapot's lid top and bottom centre are such edges.
PRT_HD inline std::uint32_t collapsed_edges(const pool::PatchControlNet& net) {
    const auto same = [](const pool::PatchPoint& a, const pool::PatchPoint& b) {
        return a.x == b.x && a.y == b.y && a.z == b.z;
    };
    std::uint32_t mask = 0;
    const int first[4] = {0, 12, 0, 3}, stride[4] = {1, 1, 4, 4};
    for (int e = 0; e < 4; ++e) {
        const pool::PatchPoint& a = net.p[first[e]];
        if (same(a, net.p[first[e] + stride[e]]) && same(a, net.p[first[e] + 2 * stride[e]]) &&
            same(a, net.p[first[e] + 3 * stride[e]]))
            mask |= 1u << e;
    }
    return mask;
}

/// Near a collapsed edge the patch is parametrized like polar coordinates around the apex A: the
/// parameter along the edge is an angle whose derivative vanishes at the apex, so Newton from a
/// leaf centre (seed 002, 5.3.2) overshoots towards the apex and loses the angle for rays passing
/// within ~1e-4 of A. This solves that case directly: to first order Q = A + s D(w), with D(w) the
/// derivative across the edge at edge parameter w, so the ray's planes give s D_p(w) = -R(A) (D_p
/// projected on the two plane normals): find w where D_p(w) is parallel to -R(A) (sign changes on
/// 17 samples, then bisection), take s from it and polish with Newton. At most 2 roots per edge.
/// D(w) is a cubic in w, D(w) = sum_k B_k(w) 3 (P_k - A) with P the control row (column) next to
/// the edge, so D_p's two coordinates are scalar cubics whose Bernstein coefficients are projected
/// once: each of the ~65 samples and bisection steps costs a cubic, not a patch evaluation (these
/// solves were the slowest warps of the teapot's frames on the GPU: rays near the lid's apex).
PRT_HD inline NewtonResult patch_apex_newton(const pool::PatchControlNet& net, std::uint32_t edge,
                                             const RayPlanes& planes, const PatchTraceParams& params,
                                             double tolerance, double max_s) {
    NewtonResult none{0.0, 0.0, 0, NewtonStatus::no_convergence};
    const int first[4] = {0, 12, 0, 3};
    const DVec3 apex = dvec3(net.p[first[edge]]);
    const double gx = -(dot(planes.n1, apex) + planes.d1), gy = -(dot(planes.n2, apex) + planes.d2);
    // (u, v) of edge parameter w at distance s from the edge.
    const auto param = [edge](double w, double s, double& u, double& v) {
        u = edge == 0 ? s : (edge == 1 ? 1.0 - s : w);
        v = edge == 2 ? s : (edge == 3 ? 1.0 - s : w);
    };
    // The inward derivative's control points 3 (P_k - A), projected on the planes' normals.
    const int inner_first[4] = {4, 8, 1, 2}, inner_stride[4] = {1, 1, 4, 4};
    double cx[4], cy[4];
    for (int k = 0; k < 4; ++k) {
        const DVec3 d = (dvec3(net.p[inner_first[edge] + k * inner_stride[edge]]) - apex) * 3.0;
        cx[k] = dot(planes.n1, d);
        cy[k] = dot(planes.n2, d);
    }
    const auto inward = [&](double w, double& px, double& py) {
        const double m = 1.0 - w;
        const double b0 = m * m * m, b1 = 3.0 * w * m * m, b2 = 3.0 * w * w * m, b3 = w * w * w;
        px = b0 * cx[0] + b1 * cx[1] + b2 * cx[2] + b3 * cx[3];
        py = b0 * cy[0] + b1 * cy[1] + b2 * cy[2] + b3 * cy[3];
    };
    if (dmax(fabs(gx), fabs(gy)) <= tolerance) {  // the ray passes through the apex itself
        NewtonResult r{0.0, 0.0, 0, NewtonStatus::converged};
        param(0.5, 0.0, r.u, r.v);
        return r;
    }
    constexpr int k_samples = 16;
    double px, py;
    inward(0.0, px, py);
    double w0 = 0.0, c0 = px * gy - py * gx;
    int found = 0;
    NewtonResult best = none;
    for (int k = 1; k <= k_samples && found < 2; ++k) {
        const double w1 = static_cast<double>(k) / k_samples;
        inward(w1, px, py);
        const double c1 = px * gy - py * gx;
        if (c0 * c1 <= 0.0) {
            double a = w0, b = w1, ca = c0;
            for (int it = 0; it < 24; ++it) {  // bisection to ~1e-8 of the sample spacing
                const double m = 0.5 * (a + b);
                inward(m, px, py);
                const double cm = px * gy - py * gx;
                if ((cm <= 0.0) == (ca <= 0.0)) {
                    a = m;
                    ca = cm;
                } else {
                    b = m;
                }
            }
            const double w = 0.5 * (a + b);
            inward(w, px, py);
            const double p2 = px * px + py * py;
            const double s = (px * gx + py * gy) / p2;  // > 0: the apex side the ray passes
            if (p2 > 0.0 && s > 0.0 && s <= max_s) {
                ++found;
                double u, v;
                param(w, s, u, v);
                const NewtonResult r = patch_newton(net, planes, u, v, params, tolerance);
                if (r.status == NewtonStatus::converged) return r;
                best = r;
            }
        }
        w0 = w1;
        c0 = c1;
    }
    return best;
}

/// Per (ray, patch) scratch state of intersect_patch.
struct PatchScratch {
    std::uint32_t collapsed = 0xffffffffu;  ///< collapsed_edges(), computed when first needed
    std::uint32_t apex_tried = 0;           ///< edges whose apex solve already ran
};

/// The apex solves for one leaf (at most one per edge, so at most four).
struct ApexRoots {
    NewtonResult root[4];
    std::uint32_t count = 0;      ///< solves run (converged or not)
    std::uint32_t collapsed = 0;  ///< collapsed_edges() of the net
    std::uint32_t tried = 0;      ///< edges solved so far for this (ray, patch), these included
};

/// The apex solves of patch_leaf_newton for leaf domain `d` (touching an edge of the patch): once
/// per collapsed edge the leaf touches and that is not in `tried` (`collapsed` = 0xffffffff: not
/// known yet). Out of line on the device (rare, and heavy in registers); the caller accepts the
/// roots in order.
PRT_HD PRT_NOINLINE inline ApexRoots patch_leaf_apex(const pool::PatchControlNet& net, PatchDomain d,
                                                     RayPlanes planes, PatchTraceParams params, double tolerance,
                                                     std::uint32_t collapsed, std::uint32_t tried) {
    ApexRoots r;
    r.collapsed = collapsed == 0xffffffffu ? collapsed_edges(net) : collapsed;
    r.tried = tried;
    const bool touches[4] = {d.u0 == 0.0, d.u1 == 1.0, d.v0 == 0.0, d.v1 == 1.0};
    for (std::uint32_t e = 0; e < 4; ++e) {
        if (!touches[e] || !((r.collapsed >> e) & 1u) || ((r.tried >> e) & 1u)) continue;
        r.tried |= 1u << e;
        // only roots within the leaves along the edge: s up to the leaf's extent across it
        const double max_s = e < 2 ? d.u1 - d.u0 : d.v1 - d.v0;
        r.root[r.count++] = patch_apex_newton(net, e, planes, params, tolerance, max_s);
    }
    return r;
}

/// Tries Newton from the centre of subpatch leaf `k` of patch `patch` (and, where the leaf touches
/// a collapsed edge and that fails, the apex solve once per edge); on a valid root nearer than
/// q.best_t updates q.best_t and `hit` (as accept_root: finish_patch_hit completes it) and returns
/// true.
template <PatchPrecision P = PatchPrecision::f64>
PRT_HD inline bool patch_leaf_newton(const PatchView& view, std::uint32_t patch, std::uint32_t k,
                                     PatchQuery& q, const PatchTraceParams& params, PatchHit& hit,
                                     PatchStats* stats, PatchScratch* scratch = nullptr) {
    const PatchDomain d = subpatch_domain(k);
    // seed 002, 5.3.2: the initial value is the centre of the leaf subpatch. Runs heading for the
    // root already accepted on this patch stop early (PatchTraceParams::duplicate_radius).
    const bool known = q.best_patch == patch;
    const double u0 = 0.5 * (d.u0 + d.u1), v0 = 0.5 * (d.v0 + d.v1);
    const double known_radius = known ? params.duplicate_radius : 0.0;
    NewtonResult nr;
    if constexpr (P == PatchPrecision::f32)
        nr = patch_newton_f32(view.nets[patch], q.planes, u0, v0, params, q.tolerance, q.best_u, q.best_v, known_radius);
    else
        nr = patch_newton(view.nets[patch], q.planes, u0, v0, params, q.tolerance, q.best_u, q.best_v, known_radius);
    if (stats) {
        ++stats->newton_runs;
        stats->newton_iterations += nr.iterations;
    }
    if (accept_root(view, patch, nr, q, params, hit)) return true;
    if (!scratch) return false;
    if (!(d.u0 == 0.0 || d.u1 == 1.0 || d.v0 == 0.0 || d.v1 == 1.0)) return false;
    // only patches with a collapsed edge go further (known after the first apex call)
    if (scratch->collapsed == 0u) return false;
    const ApexRoots ar = patch_leaf_apex(view.nets[patch], d, q.planes, params, q.tolerance, scratch->collapsed,
                                         scratch->apex_tried);
    scratch->collapsed = ar.collapsed;
    scratch->apex_tried = ar.tried;
    bool found = false;
    for (std::uint32_t i = 0; i < ar.count; ++i) {
        if (stats) {
            ++stats->newton_runs;
            stats->newton_iterations += ar.root[i].iterations;
        }
        found = accept_root(view, patch, ar.root[i], q, params, hit) || found;
    }
    return found;
}

/// seed 002, 5.3.2 and 5.4: descends the subpatch tree of `patch` front to back, skipping boxes
/// beyond the nearest hit so far, and runs Newton from every leaf reached. `root_t_near` is the
/// entry distance of the patch's box (already tested in the BVH). Returns true if a hit was
/// accepted (q.best_t and `hit` updated as by accept_root; intersect_patch completes it).
PRT_HD inline bool intersect_patch_tree(const PatchView& view, std::uint32_t patch, float root_t_near,
                                        PatchQuery& q, const PatchTraceParams& params, PatchHit& hit,
                                        PatchStats* stats, const PatchCullMask* cull = nullptr) {
    if (stats) ++stats->patches;
    const pool::SubpatchNode* nodes = view.nodes + static_cast<std::size_t>(patch) * view.subpatch_nodes;
    const std::size_t cull_base = static_cast<std::size_t>(patch) * patch_cull_words(view) * 32u;
    const bool use_cull = cull && cull->node_words && !q.ray.inside;
    // Ordered descent: at most one pending sibling per level, so depth + 1 entries suffice.
    std::uint32_t stack_node[pool::k_max_subpatch_depth + 2];
    float stack_t[pool::k_max_subpatch_depth + 2];
    std::uint32_t sp = 0;
    stack_node[sp] = 0;
    stack_t[sp++] = root_t_near;
    const std::uint32_t first_leaf = (1u << view.subpatch_depth) - 1u;
    PatchScratch scratch;
    bool found = false;
    while (sp > 0) {
        --sp;
        const std::uint32_t k = stack_node[sp];
        if (static_cast<double>(stack_t[sp]) > q.best_t) continue;  // beyond the nearest hit (5.4)
        if (k >= first_leaf) {
            if (patch_leaf_newton(view, patch, k, q, params, hit, stats, &scratch)) {
                found = true;
                if (q.any) return true;
            }
            continue;
        }
        const float limit = static_cast<float>(q.best_t);
        std::uint32_t c[2] = {2 * k + 1, 2 * k + 2};
        float tc[2] = {0.0f, 0.0f};
        bool h[2];
        for (int i = 0; i < 2; ++i) {
            if (use_cull && cull_bit(cull->node_words, cull_base + c[i])) {
                h[i] = false;
                continue;
            }
            h[i] = box_hit(q.box, nodes[c[i]].lo, nodes[c[i]].hi, limit, tc[i]);
            if (stats) ++stats->subpatch_boxes;
        }
        // Push the far child first so the near one is popped next.
        const int near_i = (h[0] && h[1]) ? (tc[1] < tc[0] ? 1 : 0) : (h[0] ? 0 : 1);
        if (h[0] && h[1] && sp < pool::k_max_subpatch_depth + 2) {
            stack_node[sp] = c[1 - near_i];
            stack_t[sp++] = tc[1 - near_i];
        }
        if (h[near_i] && sp < pool::k_max_subpatch_depth + 2) {
            stack_node[sp] = c[near_i];
            stack_t[sp++] = tc[near_i];
        }
    }
    return found;
}

/// intersect_patch_tree with the hit completed (finish_patch_hit): one (ray, patch) pair of the
/// data-parallel split (seed 002, 5.3.2-5.3.3).
PRT_HD inline bool intersect_patch(const PatchView& view, std::uint32_t patch, float root_t_near,
                                   PatchQuery& q, const PatchTraceParams& params, PatchHit& hit,
                                   PatchStats* stats, const PatchCullMask* cull = nullptr) {
    if (!intersect_patch_tree(view, patch, root_t_near, q, params, hit, stats, cull)) return false;
    finish_patch_hit(view, q, hit);
    return true;
}

// ---- Whole rays: BVH traversal with early termination (seed 002, 5.1 and 5.4) ----------------------

/// Traversal stack entries for the BVH (a valid pool's BVH is at most k_max_patch_bvh_depth deep,
/// and ordered traversal keeps at most one pending sibling per level).
inline constexpr std::uint32_t k_patch_bvh_stack = pool::k_max_patch_bvh_depth + 2;
/// Entries of the one stack of trace_patch_query: the BVH's, then those of one subpatch tree on top.
inline constexpr std::uint32_t k_patch_stack = k_patch_bvh_stack + pool::k_max_subpatch_depth + 2;

/// Runs a prepared query through the mixed hierarchy of seed 002, 5.1, front to back: children are
/// visited nearest box first, boxes beyond the nearest hit are skipped (early termination, 5.4),
/// and every subpatch leaf reached runs Newton from its centre (5.3.2-5.3.3). The right child of
/// interior BVH node i is bvh[i + 1].skip.
///
/// The two levels share one stack and one loop (entries are a BVH node, or a subpatch node of the
/// patch being entered; both boxes have the same layout), and Newton runs outside the traversal
/// loop, "while-while" (Aila and Laine 2009): a thread leaves the inner loop only when it has a
/// leaf (or nothing left), so on the GPU a warp's threads reach the expensive double-precision
/// Newton together instead of one by one between other threads' box tests. The order in which one
/// ray visits boxes and leaves is exactly the nested traversal's (intersect_patch_tree per patch),
/// so the hits are the same.
template <PatchPrecision P = PatchPrecision::f64>
PRT_HD inline bool trace_patch_query(const PatchView& view, PatchQuery& q, const PatchTraceParams& params,
                                     PatchHit& hit, PatchStats* stats, const PatchCullMask* cull) {
    if (view.bvh_node_count == 0) return false;
    const bool use_bvh_cull = cull && cull->bvh_words && !q.ray.inside;
    const bool use_node_cull = cull && cull->node_words && !q.ray.inside;
    if (use_bvh_cull && cull_bit(cull->bvh_words, 0)) return false;
    float t_root = 0.0f;
    if (stats) ++stats->bvh_nodes;
    if (!box_hit(q.box, view.bvh[0].lo, view.bvh[0].hi, static_cast<float>(q.best_t), t_root)) return false;
    // A stack entry is 8 bytes (one local-memory access): a node and its box's entry distance. The
    // node is BVH node `code`, or with k_sub_entry set subpatch node `code & ~k_sub_entry` of the
    // current patch (entries of one patch's tree lie above every BVH entry pushed before it, so
    // they are all popped before the traversal leaves that patch). BVH nodes are < 2^23.
    constexpr std::uint32_t k_sub_entry = 0x80000000u;
    constexpr std::uint32_t k_no_leaf = 0xffffffffu;
    struct alignas(8) Entry {
        std::uint32_t code;
        float t;
    };
    Entry stack[k_patch_stack];
    std::uint32_t sp = 0;
    stack[sp++] = Entry{0u, t_root};
    const std::uint32_t first_leaf = (1u << view.subpatch_depth) - 1u;
    const std::uint32_t cull_words = patch_cull_words(view);
    std::uint32_t patch = 0;                      // the patch whose subpatch tree is on the stack
    const pool::SubpatchNode* nodes = view.nodes;  // its nodes
    PatchScratch scratch;
    bool found = false;
    for (;;) {
        // Traversal until this thread holds a subpatch leaf (leaf != k_no_leaf) or is done.
        std::uint32_t leaf = k_no_leaf;
        while (sp > 0) {
            const Entry e = stack[--sp];
            const float t_near = e.t;
            if (static_cast<double>(t_near) > q.best_t) continue;  // beyond the nearest hit (5.4)
            const bool bvh_entry = (e.code & k_sub_entry) == 0u;
            const float* lo[2];
            const float* hi[2];
            std::uint32_t c[2];
            bool culled[2] = {false, false};
            if (bvh_entry) {
                const std::uint32_t i = e.code;
                const pool::PatchBvhNode& node = view.bvh[i];
                if (node.patch >= 0) {  // enter the patch: its root's box is this leaf's
                    patch = static_cast<std::uint32_t>(node.patch);
                    nodes = view.nodes + static_cast<std::size_t>(patch) * view.subpatch_nodes;
                    scratch = PatchScratch{};
                    if (stats) ++stats->patches;
                    stack[sp++] = Entry{k_sub_entry, t_near};  // subpatch root, node 0
                    continue;
                }
                c[0] = i + 1;
                c[1] = view.bvh[i + 1].skip;
                for (int j = 0; j < 2; ++j) {
                    lo[j] = view.bvh[c[j]].lo;
                    hi[j] = view.bvh[c[j]].hi;
                    if (use_bvh_cull) culled[j] = cull_bit(cull->bvh_words, c[j]);
                }
            } else {
                const std::uint32_t k = e.code & ~k_sub_entry;
                if (k >= first_leaf) {
                    leaf = k;
                    break;
                }
                const std::size_t cull_base = static_cast<std::size_t>(patch) * cull_words * 32u;
                for (int j = 0; j < 2; ++j) {
                    const std::uint32_t ck = 2 * k + 1 + static_cast<std::uint32_t>(j);
                    c[j] = ck | k_sub_entry;
                    lo[j] = nodes[ck].lo;
                    hi[j] = nodes[ck].hi;
                    if (use_node_cull) culled[j] = cull_bit(cull->node_words, cull_base + ck);
                }
            }
            const float limit = static_cast<float>(q.best_t);
            float tc[2] = {0.0f, 0.0f};
            bool h[2];
            for (int j = 0; j < 2; ++j) {
                if (culled[j]) {
                    h[j] = false;
                    continue;
                }
                h[j] = box_hit(q.box, lo[j], hi[j], limit, tc[j]);
                if (stats) ++(bvh_entry ? stats->bvh_nodes : stats->subpatch_boxes);
            }
            // Push the far child first so the near one is popped next.
            const int near_j = (h[0] && h[1]) ? (tc[1] < tc[0] ? 1 : 0) : (h[0] ? 0 : 1);
            if (h[0] && h[1] && sp < k_patch_stack) stack[sp++] = Entry{c[1 - near_j], tc[1 - near_j]};
            if (h[near_j] && sp < k_patch_stack) stack[sp++] = Entry{c[near_j], tc[near_j]};
        }
        if (leaf == k_no_leaf) break;
        if (patch_leaf_newton<P>(view, patch, leaf, q, params, hit, stats, &scratch)) {
            found = true;
            if (q.any) return true;
        }
    }
    if (found) finish_patch_hit(view, q, hit);
    return found;
}

/// The nearest hit of `ray` with the patches (t in (0, ray.t_max)). `cull` (optional) holds the
/// back-face bits built for this ray's origin; it is ignored for inside rays.
template <PatchPrecision P = PatchPrecision::f64>
PRT_HD inline bool trace_patches(const PatchView& view, const PatchRay& ray, const PatchTraceParams& params,
                                 PatchHit& hit, PatchStats* stats = nullptr,
                                 const PatchCullMask* cull = nullptr) {
    PatchQuery q;
    if (!make_patch_query(view, ray, params, false, q)) return false;
    return trace_patch_query<P>(view, q, params, hit, stats, cull);
}

/// Whether any patch meets `ray` at t in (0, ray.t_max) (shadow rays: stops at the first hit, 5.4).
template <PatchPrecision P = PatchPrecision::f64>
PRT_HD inline bool patches_occluded(const PatchView& view, const PatchRay& ray,
                                    const PatchTraceParams& params, PatchStats* stats = nullptr) {
    PatchQuery q;
    if (!make_patch_query(view, ray, params, true, q)) return false;
    PatchHit hit;
    return trace_patch_query<P>(view, q, params, hit, stats, nullptr);
}

/// seed 002, 5.3.1 (traverse kernel): the stackless depth-first walk with skip pointers, writing
/// the patches whose boxes `ray` meets before t_limit into out[0..max_out) and their box entry
/// distances into t_out (may be null). Returns how many patches were met (may exceed max_out: the
/// caller then retries with more room).
PRT_HD inline std::uint32_t patch_bvh_candidates(const PatchView& view, const PatchRay& ray, double t_limit,
                                                 std::uint32_t* out, float* t_out, std::uint32_t max_out,
                                                 PatchStats* stats = nullptr) {
    if (view.bvh_node_count == 0 || !is_finite(ray.dir) || !(dot(ray.dir, ray.dir) > 0.0)) return 0;
    const BoxRay br = make_box_ray(ray);
    const float limit = static_cast<float>(t_limit);
    std::uint32_t count = 0;
    std::uint32_t i = 0;
    while (i < view.bvh_node_count) {  // skips only move forward: at most bvh_node_count steps
        const pool::PatchBvhNode& node = view.bvh[i];
        float t_near = 0.0f;
        if (stats) ++stats->bvh_nodes;
        if (!box_hit(br, node.lo, node.hi, limit, t_near)) {
            i = node.skip;
            continue;
        }
        if (node.patch >= 0) {
            if (count < max_out) {
                out[count] = static_cast<std::uint32_t>(node.patch);
                if (t_out) t_out[count] = t_near;
            }
            ++count;
        }
        ++i;
    }
    return count;
}

// ---- Back-face culling per view (seed 002, 5.2) ------------------------------------------------------

/// Whether every point of subpatch node `n` faces away from `eye`: for all p in the node's box and
/// every normal m in its cone, (p - eye) . m > 0. Conservative (the cone bounds all normals,
/// the bounding sphere of the box all directions from the eye):
///   angle(c - eye, axis) + asin(r / |c - eye|) + cone half-angle < 90 degrees.
/// seed 002 tests only the four corner normals; this test never culls a visible front face.
PRT_HD inline bool subpatch_backfacing(const pool::SubpatchNode& n, DVec3 eye) {
    if (!(n.cone_cos > 0.0f)) return false;
    const DVec3 lo{n.lo[0], n.lo[1], n.lo[2]}, hi{n.hi[0], n.hi[1], n.hi[2]};
    const DVec3 c = (lo + hi) * 0.5;
    const double r = 0.5 * length(hi - lo);
    const DVec3 w = c - eye;
    const double d = length(w);
    if (!(d > r)) return false;
    const DVec3 axis = octahedral_decode(n.cone_axis);
    const double alpha = acos(fmin(fmax(dot(w, axis) / d, -1.0), 1.0));
    const double beta = asin(fmin(r / d, 1.0));
    const double theta = acos(fmin(static_cast<double>(n.cone_cos), 1.0));
    return alpha + beta + theta < 1.5707963267948966 - 1e-6;
}

/// Marks the back-facing nodes of one patch's subpatch tree for eye position `eye` (one thread per
/// patch): node k is culled when it is back-facing itself or both its children are (5.2: "the
/// flags of the subpatches are propagated up using an AND operation"). Writes words
/// [patch * patch_cull_words, +patch_cull_words) of node_words.
PRT_HD inline void mark_backfacing_patch(const PatchView& view, std::uint32_t patch, DVec3 eye,
                                         std::uint32_t* node_words) {
    const std::uint32_t words = patch_cull_words(view);
    std::uint32_t* w = node_words + static_cast<std::size_t>(patch) * words;
    for (std::uint32_t i = 0; i < words; ++i) w[i] = 0;
    const pool::SubpatchNode* nodes = view.nodes + static_cast<std::size_t>(patch) * view.subpatch_nodes;
    const std::uint32_t first_leaf = (1u << view.subpatch_depth) - 1u;
    for (std::uint32_t k = view.subpatch_nodes; k-- > 0;) {  // children (2k+1, 2k+2) before parents
        bool culled = subpatch_backfacing(nodes[k], eye);
        if (!culled && k < first_leaf) culled = cull_bit(w, 2 * k + 1) && cull_bit(w, 2 * k + 2);
        if (culled) w[k >> 5] |= 1u << (k & 31u);
    }
}

/// Propagates the patches' root bits up the BVH (after mark_backfacing_patch for every patch): a
/// leaf is culled with its patch's root, an interior node when both children are. Sequential over
/// the nodes (children follow their parent in the depth-first layout, so walk backwards).
PRT_HD inline void mark_backfacing_bvh(const PatchView& view, const std::uint32_t* node_words,
                                       std::uint32_t* bvh_words) {
    const std::uint32_t words = bvh_cull_words(view);
    for (std::uint32_t i = 0; i < words; ++i) bvh_words[i] = 0;
    const std::size_t patch_bits = static_cast<std::size_t>(patch_cull_words(view)) * 32u;
    for (std::uint32_t i = view.bvh_node_count; i-- > 0;) {
        const pool::PatchBvhNode& node = view.bvh[i];
        const bool culled = node.patch >= 0
                                ? cull_bit(node_words, static_cast<std::size_t>(node.patch) * patch_bits)
                                : cull_bit(bvh_words, i + 1) && cull_bit(bvh_words, view.bvh[i + 1].skip);
        if (culled) bvh_words[i >> 5] |= 1u << (i & 31u);
    }
}

}  // namespace prt::core
