// PointRT preprocess: probe-ray culling of replicated splats (thesis 3.4) and the hole-rate
// measurement that says what the culling cost.
//
// thesis 3.4: prt-octree stores every splat in every leaf its disk overlaps, so that a ray crossing
// a leaf finds the disks that cover the surface inside it; that costs 5-10x the input's memory. Most
// replicas are redundant: the leaf's own splats (those whose centre lies in it) already cover most
// of the surface inside it. Culling shoots probe rays through each filled leaf from many directions
// and keeps only the replicas some probe needs:
//
//   leaf L, box B, splats S(L) = centre splats C(L) + replicas R(L)
//   for each probe direction d (spread over a hemisphere, randomly rotated per leaf)
//     for each cell of a jittered G x G grid over the projection across d of the part of B that
//     L's disks reach
//       walk the probe line through the octree (the renderer's walk_next) to L's range [t0, t1]
//       intersect every splat of L there (the renderer's intersect_splat); the line is two probe
//       rays, along d (disks facing -d) and along -d (disks facing d), each handled as below
//       thesis policy: no hit on C(L) -> keep every replica it hits
//       greedy policy: the nearest kept hit (C(L) + replicas kept so far) must lie inside the
//                      blending window of the nearest hit of all of S(L) (t_near + window * R_near);
//                      else keep the one replica hit inside that window closest to its centre
//       votes policy:  greedy, but the replica picked is the one that most probes not covered by
//                      C(L) hit inside their window (the thesis's per-splat hit counter as priority)
//
// "Greedy" is what the issue asks for ("better, the splats kept so far"): a replica is only kept
// for a probe that nothing kept so far serves, so overlapping replicas no longer all survive. The
// window test (rather than "any hit") means a probe also counts as unserved when a kept splat
// only hits it deeper than the surface it saw in the unculled leaf (the back of a thin part), so
// every probe sees the same surface, within the blending window, before and after culling.
//
// The first half of this header is device-callable (PRT_HD, no STL, no allocation, no recursion):
// the CPU path (cull.cpp) and the CUDA path (runtime/cuda/src/cull.cu) run the same functions.
// Probe directions come from a table computed once on the host (no transcendental functions in
// the per-probe code), so the two backends shoot bit-identical probes when the CUDA code is
// compiled without FMA contraction (it is: --fmad=false).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "prt/core/octree.h"
#include "prt/core/splat.h"
#include "prt/formats/pool_layout.h"

namespace prt::pre {

// ==== Device-callable part =======================================================================

/// Which replicas survive (see the header comment).
enum class CullPolicy : std::uint32_t {
    thesis = 0,  ///< thesis 3.4 literally: every replica hit by a probe that misses the centre splats
    greedy =
        1,  ///< probes test the splats kept so far; one replica (hit nearest its centre) per unserved probe
    votes = 2,  ///< greedy, choosing the replica most unserved probes hit (thesis's counters as priority)
};

/// Values of the per-stored-splat keep flags.
enum KeepFlag : std::uint8_t {
    k_keep_none = 0,    ///< a replica no probe needed (so far)
    k_keep_centre = 1,  ///< the splat's centre lies in the leaf's closed box: never removed
    k_keep_probe = 2,   ///< a replica some probe needed
};

/// One probe direction and an orthonormal basis (u, v) of the plane across it.
struct ProbeDirection {
    core::Vec3 d, u, v;
};

/// A filled leaf as culling sees it: its node word (to recognise it during a walk), level and
/// integer cell coordinates at that level. level == k_cull_leaf_unknown: no node references the
/// leaf (never produced by prt-octree); culling then keeps its splats.
struct CullLeaf {
    std::uint32_t node;
    std::uint32_t level;
    std::uint32_t cell[3];
};
inline constexpr std::uint32_t k_cull_leaf_unknown = 0xffffffffu;

/// Everything the per-leaf culling reads, as non-owning views (host or device memory).
struct CullView {
    core::OctreeView octree;                     ///< the replicated input octree
    const CullLeaf* leaves = nullptr;            ///< octree.filled_leaves entries, by leaf_info index
    const ProbeDirection* directions = nullptr;  ///< direction_sets x directions_per_set
    std::uint32_t direction_sets = 0;
    std::uint32_t directions_per_set = 0;
    std::uint32_t grid = 0;  ///< G: G x G probe lines per direction
    CullPolicy policy = CullPolicy::greedy;
    float window = 1.0f;     ///< blending window in radii of the nearest splat (RenderParams::blend_window)
    std::uint32_t seed = 0;  ///< jitter and direction-set choice
    /// Leaves one probe walk may visit: it starts within 1/32 of the leaf's edge of the leaf, so it
    /// needs a few steps; a walk cut by the bound is no probe.
    std::uint32_t max_steps = 64;
};

/// Per-leaf counters, summed by the backends.
struct CullCounters {
    std::uint64_t probes = 0;           ///< probe rays (two per line) whose walk reached their leaf
    std::uint64_t probes_hit = 0;       ///< of those, probe rays that hit a splat of the leaf
    std::uint64_t probes_unserved = 0;  ///< probe rays that made a replica kept
    std::uint64_t splat_tests = 0;
    CullCounters& operator+=(const CullCounters& o) {
        probes += o.probes;
        probes_hit += o.probes_hit;
        probes_unserved += o.probes_unserved;
        splat_tests += o.splat_tests;
        return *this;
    }
};

namespace detail {

/// A 32-bit integer hash (lowbias32, C. Wellons): decorrelates leaf and probe indices.
PRT_HD PRT_INLINE std::uint32_t hash32(std::uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/// A float in [0, 1) from the top 24 bits of a hash (exact on every backend).
PRT_HD PRT_INLINE float unit_float(std::uint32_t h) {
    return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

/// What a probe line found among a leaf's splats on one of its two sides. Side 0 is the ray
/// o + t d (faces with d.n < 0, as an outside ray sees them), side 1 the reverse ray o - t' d
/// (faces with d.n > 0, met in decreasing t). Both sides measure distance along their own ray,
/// s = t on side 0 and s = -t on side 1, so "nearest" is the smallest s on both.
struct SideHits {
    float near_s;  ///< nearest hit of any splat (k_inf: none)
    float near_r;  ///< its radius
    float kept_s;  ///< nearest hit of a splat whose keep flag is >= kept_min (k_inf: none)
    bool centre;   ///< some centre splat is hit
};

/// The ray-parameter interval [lo, hi] of side `side` for distances [s0, s1] along that side,
/// clipped to the leaf's range [t0, t1] (hits outside it belong to other leaves).
PRT_HD PRT_INLINE void side_interval(std::uint32_t side, float s0, float s1, float t0, float t1, float& lo,
                                     float& hi) {
    lo = fmaxf(side ? -s1 : s0, t0);
    hi = fminf(side ? -s0 : s1, t1);
}

/// One pass over splats [begin, end): both sides' hits with t in [t0, t1] (core::intersect_splat,
/// the renderer's test, with the face each side expects).
PRT_HD PRT_INLINE void probe_hits(const core::OctreeView& v, std::uint32_t begin, std::uint32_t end,
                                  const std::uint8_t* keep, std::uint8_t kept_min, core::Vec3 o, core::Vec3 d,
                                  float t0, float t1, SideHits hits[2], CullCounters& c) {
    PRT_UNROLL
    for (int side = 0; side < 2; ++side) hits[side] = SideHits{core::k_inf, 0.0f, core::k_inf, false};
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = core::load_splat(v.splats + i);
        const bool side = core::dot(d, core::vec3(s.normal)) > 0.0f;
        float t, xr;
        ++c.splat_tests;
        if (!core::intersect_splat(s, o, d, side, t0, t1, t, xr)) continue;
        SideHits& h = hits[side ? 1 : 0];
        const float sd = side ? -t : t;
        if (sd < h.near_s) {
            h.near_s = sd;
            h.near_r = s.radius;
        }
        if (keep[i] >= kept_min && sd < h.kept_s) h.kept_s = sd;
        h.centre = h.centre || keep[i] == k_keep_centre;
    }
}

}  // namespace detail

/// The number of probe lines per leaf: directions x G x G (each line is two probe rays).
PRT_HD PRT_INLINE std::uint32_t probes_per_leaf(const CullView& v) {
    return v.directions_per_set * v.grid * v.grid;
}

/// Where the probes of a leaf aim: the polytope P = (leaf box, clipped to the bounding box of the
/// leaf's disks) n (a slab across the disks' mean normal n holding every disk: s0 <= n.x - n.c <=
/// s1), grown by 1/64 of the leaf's edge on every side. Every hit the renderer can accept in the
/// leaf lies in P, and where the surface is a sheet through the leaf P is a thin slice of it, so
/// probe lines spread over P's projection hit the surface far more often than lines spread over
/// the whole cell, and every leaf, even one the surface only clips at a corner, gets its G x G
/// lines per direction on its own piece of surface.
struct ProbeRegion {
    core::Vec3 centre;  ///< the leaf box's centre; everything below is relative to it
    core::Vec3 lo, hi;  ///< the clipped box
    core::Vec3 n;       ///< slab normal (unit)
    float s0, s1;       ///< slab bounds along n
    float margin;
    std::uint32_t corner_count;  ///< vertices of P (at most 8 box corners + 24 edge/plane crossings)
    core::Vec3 corners[32];
};

/// Builds a leaf's ProbeRegion. Returns false when the leaf is unknown, has no splats or P is empty.
PRT_HD inline bool probe_region(const CullView& v, std::uint32_t leaf, ProbeRegion& r) {
    using core::Vec3;
    const CullLeaf L = v.leaves[leaf];
    if (L.level == k_cull_leaf_unknown) return false;
    std::uint32_t begin, end;
    core::leaf_splats(v.octree, L.node, begin, end);
    if (begin == end) return false;
    const float size = v.octree.root_size * core::exp2_neg(L.level);
    r.centre =
        v.octree.root_min + Vec3{static_cast<float>(L.cell[0]) + 0.5f, static_cast<float>(L.cell[1]) + 0.5f,
                                 static_cast<float>(L.cell[2]) + 0.5f} *
                                size;
    r.margin = size * (1.0f / 64.0f);
    Vec3 lo = core::vec3(core::k_inf), hi = core::vec3(-core::k_inf), nsum{0, 0, 0};
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = core::load_splat(v.octree.splats + i);
        const Vec3 n = core::vec3(s.normal), c = core::vec3(s.position) - r.centre;
        // a disk's extent along an axis a: r sqrt(1 - n_a^2)
        const Vec3 e{s.radius * sqrtf(fmaxf(0.0f, 1.0f - n.x * n.x)),
                     s.radius * sqrtf(fmaxf(0.0f, 1.0f - n.y * n.y)),
                     s.radius * sqrtf(fmaxf(0.0f, 1.0f - n.z * n.z))};
        lo = core::vmin(lo, c - e);
        hi = core::vmax(hi, c + e);
        nsum += n;
    }
    r.n = core::normalize_or(nsum, Vec3{0.0f, 0.0f, 1.0f});
    r.s0 = core::k_inf;
    r.s1 = -core::k_inf;
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = core::load_splat(v.octree.splats + i);
        const float cn = core::dot(r.n, core::vec3(s.normal));
        const float e = s.radius * sqrtf(fmaxf(0.0f, 1.0f - cn * cn));  // the disk's extent along n
        const float m = core::dot(r.n, core::vec3(s.position) - r.centre);
        r.s0 = fminf(r.s0, m - e);
        r.s1 = fmaxf(r.s1, m + e);
    }
    r.s0 -= r.margin;
    r.s1 += r.margin;
    const float half = 0.5f * size;
    r.lo = core::vmax(lo, core::vec3(-half)) - core::vec3(r.margin);
    r.hi = core::vmin(hi, core::vec3(half)) + core::vec3(r.margin);
    if (!(r.lo.x <= r.hi.x && r.lo.y <= r.hi.y && r.lo.z <= r.hi.z)) return false;
    // Vertices of P: box corners inside the slab, and where box edges cross the slab's planes.
    r.corner_count = 0;
    for (std::uint32_t c = 0; c < 8; ++c) {
        const Vec3 p{(c & 1u) ? r.hi.x : r.lo.x, (c & 2u) ? r.hi.y : r.lo.y, (c & 4u) ? r.hi.z : r.lo.z};
        const float m = core::dot(r.n, p);
        if (m >= r.s0 && m <= r.s1) r.corners[r.corner_count++] = p;
    }
    for (std::uint32_t axis = 0; axis < 3; ++axis) {
        for (std::uint32_t e = 0; e < 4; ++e) {  // the 4 box edges along `axis`
            const std::uint32_t b1 = (axis + 1) % 3, b2 = (axis + 2) % 3;
            float pa[3], pb[3];
            pa[axis] = core::component(r.lo, static_cast<int>(axis));
            pb[axis] = core::component(r.hi, static_cast<int>(axis));
            pa[b1] = pb[b1] = core::component((e & 1u) ? r.hi : r.lo, static_cast<int>(b1));
            pa[b2] = pb[b2] = core::component((e & 2u) ? r.hi : r.lo, static_cast<int>(b2));
            const Vec3 a{pa[0], pa[1], pa[2]}, b{pb[0], pb[1], pb[2]};
            const float ma = core::dot(r.n, a), mb = core::dot(r.n, b);
            for (int k = 0; k < 2; ++k) {
                const float s = k ? r.s1 : r.s0;
                if (!((ma - s) * (mb - s) < 0.0f)) continue;
                const float f = (s - ma) / (mb - ma);
                r.corners[r.corner_count++] = a + (b - a) * f;
            }
        }
    }
    return r.corner_count > 0;
}

/// The grid frame of one probe direction of a leaf: the direction, and the extents of P's
/// projection across it (u, v) and along it (d), relative to ProbeRegion::centre.
struct ProbeFrame {
    ProbeDirection dir;
    float u0, u1, v0, v1, d0, d1;
};

/// The frame of direction `di` (< directions_per_set) of leaf `leaf`: one of the 64 rotated
/// direction sets, picked by a hash of the leaf index and the seed.
PRT_HD inline void probe_frame(const CullView& v, std::uint32_t leaf, const ProbeRegion& r, std::uint32_t di,
                               ProbeFrame& f) {
    const std::uint32_t leaf_hash = detail::hash32(leaf ^ detail::hash32(v.seed));
    f.dir = v.directions[(leaf_hash % v.direction_sets) * v.directions_per_set + di];
    f.u0 = f.v0 = f.d0 = core::k_inf;
    f.u1 = f.v1 = f.d1 = -core::k_inf;
    for (std::uint32_t i = 0; i < r.corner_count; ++i) {
        const float pu = core::dot(f.dir.u, r.corners[i]), pv = core::dot(f.dir.v, r.corners[i]),
                    pd = core::dot(f.dir.d, r.corners[i]);
        f.u0 = fminf(f.u0, pu);
        f.u1 = fmaxf(f.u1, pu);
        f.v0 = fminf(f.v0, pv);
        f.v1 = fmaxf(f.v1, pv);
        f.d0 = fminf(f.d0, pd);
        f.d1 = fmaxf(f.d1, pd);
    }
}

/// Probe line `k` of filled leaf `leaf` (thesis 3.4: "raytrace it from various viewpoints using a
/// set of probe rays"): direction k / G^2 (`f`, from probe_frame()), through a jittered point of
/// cell k % G^2 of a G x G grid over P's projection across that direction. The line o + t d
/// (model local frame, d unit) starts a margin before P and ends a margin behind it, t in
/// [0, t_max). Returns false when the line misses P (then it is no probe).
PRT_HD inline bool make_probe(const CullView& v, std::uint32_t leaf, const ProbeRegion& r,
                              const ProbeFrame& f, std::uint32_t k, core::Vec3& o, core::Vec3& d,
                              float& t_max) {
    using core::Vec3;
    const std::uint32_t cell = k % (v.grid * v.grid);
    const std::uint32_t gi = cell % v.grid, gj = cell / v.grid;
    const std::uint32_t h = detail::hash32(detail::hash32(leaf ^ detail::hash32(v.seed)) + k * 0x9e3779b9u);
    const float inv_g = 1.0f / static_cast<float>(v.grid);
    const float a = f.u0 + (f.u1 - f.u0) * ((static_cast<float>(gi) + detail::unit_float(h)) * inv_g);
    const float b =
        f.v0 + (f.v1 - f.v0) * ((static_cast<float>(gj) + detail::unit_float(detail::hash32(h))) * inv_g);
    d = f.dir.d;
    const Vec3 rel = f.dir.u * a + f.dir.v * b + d * (f.d0 - r.margin);  // relative to r.centre
    o = r.centre + rel;
    t_max = f.d1 - f.d0 + 2.0f * r.margin;
    // Does the line meet P (the box and the slab)? Grid points outside P's projection do not.
    float e0 = 0.0f, e1 = t_max;
    PRT_UNROLL
    for (int ax = 0; ax < 4; ++ax) {
        const Vec3 axis =
            ax == 3 ? r.n : Vec3{ax == 0 ? 1.0f : 0.0f, ax == 1 ? 1.0f : 0.0f, ax == 2 ? 1.0f : 0.0f};
        const float dc = core::dot(axis, d), oc = core::dot(axis, rel);
        const float l = ax == 3 ? r.s0 : core::component(r.lo, ax),
                    u = ax == 3 ? r.s1 : core::component(r.hi, ax);
        if (dc == 0.0f) {
            if (!(oc >= l && oc <= u)) return false;
            continue;
        }
        const float inv = 1.0f / dc;
        const float ta = (l - oc) * inv, tb = (u - oc) * inv;
        e0 = fmaxf(e0, fminf(ta, tb));
        e1 = fminf(e1, fmaxf(ta, tb));
    }
    return e0 <= e1;
}

/// The probe's parameter range inside its leaf, exactly as the renderer computes it: the ray is
/// walked through the octree (thesis 2.2.1, core::walk_next) until it reaches the leaf. Returns
/// false when the walk does not reach the leaf (the probe grazes an edge or corner).
PRT_HD inline bool probe_leaf_range(const CullView& v, std::uint32_t leaf, core::Vec3 o, core::Vec3 d,
                                    float t_max, float& t0, float& t1) {
    core::OctreeWalk w;
    if (!core::walk_begin(v.octree, o, d, 0.0f, t_max, v.max_steps, w)) return false;
    const std::uint32_t node = v.leaves[leaf].node;
    core::OctreeLeaf l;
    while (core::walk_next(v.octree, w, l)) {  // bounded by max_steps
        if (l.node == node) {
            t0 = l.t0;
            t1 = l.t1;
            return t0 <= t1;
        }
    }
    return false;
}

/// thesis 3.4: culls the replicas of filled leaf `leaf`. `keep` holds one flag per stored splat:
/// on entry k_keep_centre for the leaf's centre splats and k_keep_none for its replicas; on return
/// the replicas a probe needed are k_keep_probe. `votes` (one counter per stored splat, zero on
/// entry) is scratch for the votes policy and may be null otherwise. Only the leaf's own ranges of
/// `keep` and `votes` are touched, so leaves can be culled in parallel.
///
/// Each probe line is two probe rays: o + t d and its reverse. A disk facing d is met by the
/// reverse ray only, so one pass over the splats serves both, and each leaf is probed from
/// 2 x directions directions without testing any line twice.
PRT_HD inline void cull_leaf(const CullView& v, std::uint32_t leaf, std::uint8_t* keep, std::uint32_t* votes,
                             CullCounters& c) {
    const CullLeaf L = v.leaves[leaf];
    if (L.level == k_cull_leaf_unknown) return;
    std::uint32_t begin, end;
    core::leaf_splats(v.octree, L.node, begin, end);
    bool replicas = false;
    for (std::uint32_t i = begin; i < end && !replicas; ++i) replicas = keep[i] == k_keep_none;
    if (!replicas) return;
    ProbeRegion region;
    if (!probe_region(v, leaf, region)) {
        // Nothing to aim at (cannot happen for disks that overlap the leaf, short of rounding):
        // keep what could not be examined.
        for (std::uint32_t i = begin; i < end; ++i)
            if (keep[i] == k_keep_none) keep[i] = k_keep_probe;
        return;
    }
    const std::uint32_t lines = probes_per_leaf(v);
    const std::uint32_t per_dir = v.grid * v.grid;
    ProbeFrame frame{};
    const bool use_votes = v.policy == CullPolicy::votes && votes != nullptr;
    const pool::Splat* splats = v.octree.splats;
    // Votes pass: every probe ray the centre splats do not serve votes for each replica it hits
    // inside its blending window (thesis 3.4's per-splat counter).
    for (std::uint32_t k = 0; use_votes && k < lines; ++k) {
        core::Vec3 o, d;
        float t_max, t0, t1;
        if (k % per_dir == 0) probe_frame(v, leaf, region, k / per_dir, frame);
        if (!make_probe(v, leaf, region, frame, k, o, d, t_max) ||
            !probe_leaf_range(v, leaf, o, d, t_max, t0, t1))
            continue;
        detail::SideHits hits[2];
        detail::probe_hits(v.octree, begin, end, keep, k_keep_centre, o, d, t0, t1, hits, c);
        for (std::uint32_t side = 0; side < 2; ++side) {
            const detail::SideHits& h = hits[side];
            if (!(h.near_s < core::k_inf)) continue;
            const float w_end = h.near_s + v.window * h.near_r;
            if (h.kept_s <= w_end) continue;
            float lo, hi;
            detail::side_interval(side, h.near_s, w_end, t0, t1, lo, hi);
            for (std::uint32_t i = begin; i < end; ++i) {
                if (keep[i] != k_keep_none) continue;
                float t, xr;
                ++c.splat_tests;
                if (core::intersect_splat(core::load_splat(splats + i), o, d, side != 0, lo, hi, t, xr))
                    ++votes[i];
            }
        }
    }
    for (std::uint32_t k = 0; k < lines; ++k) {
        core::Vec3 o, d;
        float t_max, t0, t1;
        if (k % per_dir == 0) probe_frame(v, leaf, region, k / per_dir, frame);
        if (!make_probe(v, leaf, region, frame, k, o, d, t_max) ||
            !probe_leaf_range(v, leaf, o, d, t_max, t0, t1))
            continue;
        c.probes += 2;
        detail::SideHits hits[2];
        detail::probe_hits(v.octree, begin, end, keep, k_keep_centre, o, d, t0, t1, hits, c);

        for (std::uint32_t side = 0; side < 2; ++side) {
            const detail::SideHits& h = hits[side];
            if (!(h.near_s < core::k_inf)) continue;
            ++c.probes_hit;
            if (v.policy == CullPolicy::thesis) {
                // thesis 3.4: a probe through the leaf that misses the leaf's original (centre)
                // splats keeps every replica it hits.
                if (h.centre) continue;
                ++c.probes_unserved;
                for (std::uint32_t i = begin; i < end; ++i) {
                    if (keep[i] != k_keep_none) continue;
                    float t, xr;
                    ++c.splat_tests;
                    if (core::intersect_splat(core::load_splat(splats + i), o, d, side != 0, t0, t1, t, xr))
                        keep[i] = k_keep_probe;
                }
                continue;
            }
            // Greedy: served when a kept splat is hit inside the blending window of the nearest hit.
            const float w_end = h.near_s + v.window * h.near_r;
            if (h.kept_s <= w_end) continue;
            // Unserved: keep one replica hit inside the window, the most voted for (votes policy)
            // or the one hit nearest its centre (its disk covers the most around this probe).
            float lo, hi;
            detail::side_interval(side, h.near_s, w_end, t0, t1, lo, hi);
            std::uint32_t best = end, best_votes = 0;
            float best_xr = 2.0f;
            for (std::uint32_t i = begin; i < end; ++i) {
                if (keep[i] != k_keep_none) continue;
                float t, xr;
                ++c.splat_tests;
                if (!core::intersect_splat(core::load_splat(splats + i), o, d, side != 0, lo, hi, t, xr))
                    continue;
                const std::uint32_t vi = use_votes ? votes[i] : 0u;
                if (best == end || vi > best_votes || (vi == best_votes && xr < best_xr)) {
                    best = i;
                    best_votes = vi;
                    best_xr = xr;
                }
            }
            if (best != end) {
                keep[best] = k_keep_probe;
                ++c.probes_unserved;
            }
        }
    }
}

/// One ray of the hole-rate measurement, traced through the unculled and the culled octree with
/// the renderer's closest-hit function (thesis 3.3 blending). `inside`: the ray expects back faces
/// (a refracted ray inside a model, thesis 3.6), else front faces (primary rays).
struct HoleSample {
    float t_full, t_culled;       ///< blended hit parameters (valid when hit)
    core::Vec3 n_full, n_culled;  ///< blended normals
    std::uint32_t hit_full, hit_culled;
};

PRT_HD inline void trace_hole_ray(const core::OctreeView& full, const core::OctreeView& culled, core::Vec3 o,
                                  core::Vec3 d, bool inside, const core::BlendOptions& blend,
                                  std::uint32_t max_steps, HoleSample& out) {
    core::WalkStats ws;
    core::SplatSample a{}, b{};
    out.hit_full =
        core::closest_hit_splats(full, nullptr, o, d, inside, core::k_inf, blend, max_steps, a, ws);
    out.hit_culled =
        core::closest_hit_splats(culled, nullptr, o, d, inside, core::k_inf, blend, max_steps, b, ws);
    out.t_full = a.t;
    out.t_culled = b.t;
    out.n_full = a.normal;
    out.n_culled = b.normal;
}

// ==== Host part ===================================================================================

/// The four octree sections of a pool (views; pool::PoolFile or a built SplatOctree owns them).
struct OctreeSections {
    pool::OctreeInfo info{};
    std::span<const std::uint32_t> nodes;
    std::span<const std::uint32_t> leaf_info;
    std::span<const pool::Splat> splats;
};

/// The core's view of octree sections (the renderer's OctreeView).
core::OctreeView octree_view(const OctreeSections& s);

struct CullParams {
    /// Probe line directions per leaf, spread evenly over a hemisphere; each line is probed both
    /// ways, so a leaf is probed from 2 x directions directions. Each leaf uses one of 64 random
    /// rotations of the set. Default (with grid) chosen by measurement: cull.cpp's header comment.
    std::uint32_t directions = 4;
    /// G: a G x G jittered grid of parallel probe lines per direction.
    std::uint32_t grid = 8;
    CullPolicy policy = CullPolicy::greedy;
    float window = 1.0f;  ///< blending window in radii (RenderParams::blend_window, the renderer's default)
    std::uint32_t seed = 1;
    unsigned threads = 0;  ///< CPU worker threads; 0 = every hardware thread
    /// "cpu", "cuda" or "auto" (cuda when this build has it and a device is usable).
    std::string backend = "auto";
    /// Progress, called from one thread with (leaves done, leaves); may be empty.
    std::function<void(std::uint64_t, std::uint64_t)> progress;
};

struct CullStats {
    std::string backend;  ///< the backend that ran ("cpu" or "cuda: DEVICE")
    std::uint64_t leaves = 0, leaves_with_replicas = 0;
    std::uint64_t unique_splats = 0;  ///< OctreeInfo::unique_splats
    std::uint64_t splats_before = 0, splats_after = 0;
    std::uint64_t centre_splats = 0;  ///< stored splats whose centre lies in their leaf (kept)
    std::uint64_t replicas_before = 0, replicas_kept = 0;
    std::uint64_t bytes_before = 0, bytes_after = 0;  ///< payload of leaf_info + splats
    CullCounters counters;
    double seconds = 0;  ///< culling (probing) time, without reading and writing pools
    double replication_before() const {
        return unique_splats ? double(splats_before) / double(unique_splats) : 0;
    }
    double replication_after() const {
        return unique_splats ? double(splats_after) / double(unique_splats) : 0;
    }
};

/// The culled octree: the node pool is unchanged (the input's); leaf_info and splats are rewritten,
/// octree_info gets the new splat count and k_octree_culled.
struct CulledOctree {
    pool::OctreeInfo info{};
    std::vector<std::uint32_t> leaf_info;
    std::vector<pool::Splat> splats;
};

/// The filled leaves of an octree (level, cell, node word by leaf_info index), found by walking
/// the node pool from the root. Throws prt::Error on a malformed tree.
std::vector<CullLeaf> collect_leaves(const OctreeSections& s);

/// The probe direction table: `sets` random rotations of `directions` directions spread evenly over
/// a hemisphere (a Fibonacci spiral).
std::vector<ProbeDirection> make_probe_directions(std::uint32_t directions, std::uint32_t sets,
                                                  std::uint32_t seed);

/// Initial keep flags: k_keep_centre where the splat's centre lies in its leaf's closed box
/// (node_box(), the builder's test), k_keep_none elsewhere; every splat of an unknown leaf is kept.
std::vector<std::uint8_t> centre_flags(const OctreeSections& s, std::span<const CullLeaf> leaves);

/// The backend culling would use for `name` ("cpu", "cuda", "auto"). Throws prt::Error when `name`
/// is "cuda" and no CUDA device is usable (or the build has no CUDA), or `name` is unknown. `why`
/// gets a note when "auto" falls back to the CPU.
std::string resolve_cull_backend(const std::string& name, std::string* why = nullptr);

/// Runs the per-leaf culling and returns the final keep flags (one per stored splat). Throws
/// prt::Error on invalid parameters or an octree that is not replicated.
std::vector<std::uint8_t> cull_keep_flags(const OctreeSections& s, const CullParams& params,
                                          CullStats* stats = nullptr);

/// Culls an octree (thesis 3.4): cull_keep_flags(), then the kept splats in their leaf order.
CulledOctree cull_octree(const OctreeSections& s, const CullParams& params, CullStats* stats = nullptr);

// ---- Hole rate -----------------------------------------------------------------------------------

/// Ray families of the hole measurement.
enum class HoleFamily : std::uint32_t {
    sphere = 0,   ///< from a random point of the bounding sphere towards a random point of the bounds
    reverse = 1,  ///< the same, traced as inside rays: they see back faces, as refracted rays do
    orbit = 2,    ///< pinhole views (64 x 64 jittered pixels, 40 degrees) from outside, looking at the centre
    inside = 3,  ///< pinhole views (64 x 64 jittered pixels, 90 degrees) from random points inside the bounds
};
inline constexpr std::uint32_t k_hole_families = 4;
const char* hole_family_name(HoleFamily f);

struct HoleRay {
    core::Vec3 o, d;       ///< model local frame, d unit
    std::uint32_t inside;  ///< 1: an inside ray (expects back faces)
};

/// N rays, families in order: 40 % sphere, 10 % reverse, 25 % orbit, 25 % inside (views of up to
/// 4096 rays). `family_begin` gets the first index of each family (plus N at the end).
/// Deterministic in `seed`. The bounds are the splats' (centre +- radius).
std::vector<HoleRay> make_hole_rays(std::span<const pool::Splat> splats, std::uint64_t n, std::uint64_t seed,
                                    std::uint64_t family_begin[k_hole_families + 1]);

/// Tolerance of the hole measurement: a culled hit farther than this many mean splat radii from
/// the unculled one (along the ray) is on another surface: the ray went through a hole.
inline constexpr double k_hole_tolerance_radii = 3.0;

struct HoleCounts {
    std::uint64_t rays = 0;
    std::uint64_t hit_full = 0;  ///< rays that hit the unculled surface
    std::uint64_t missed = 0;    ///< of those, rays that miss the culled surface entirely
    std::uint64_t wrong_surface =
        0;                        ///< of those, rays whose culled hit is k_hole_tolerance_radii away or more
    std::uint64_t spurious = 0;   ///< miss the unculled surface, hit the culled one (impossible: must be 0)
    double normal_error_sum = 0;  ///< degrees between the blended normals, over rays that are no holes
    std::uint64_t normal_count = 0;
    std::uint64_t holes() const { return missed + wrong_surface; }
    /// Rays that hit the unculled surface but miss the culled one there, over rays that hit the
    /// unculled surface.
    double hole_rate() const { return hit_full ? double(holes()) / double(hit_full) : 0.0; }
    double miss_rate() const { return hit_full ? double(missed) / double(hit_full) : 0.0; }
    double mean_normal_error() const { return normal_count ? normal_error_sum / double(normal_count) : 0.0; }
    HoleCounts& operator+=(const HoleCounts& o);
};

struct HoleStats {
    HoleCounts total;
    HoleCounts family[k_hole_families];
    std::string backend;
    double seconds = 0;
};

struct HoleParams {
    std::uint64_t rays = 1000000;
    std::uint64_t seed = 7;
    float window = 1.0f;  ///< blending window (RenderParams::blend_window)
    unsigned threads = 0;
    std::string backend = "auto";
};

/// Shoots HoleParams::rays rays (make_hole_rays) at both octrees and counts rays that hit the
/// unculled surface but miss the culled one. Both octrees must share their node pool and frame.
HoleStats measure_holes(const OctreeSections& full, const OctreeSections& culled, const HoleParams& params);

}  // namespace prt::pre
