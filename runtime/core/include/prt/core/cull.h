// PointRT core: the device-callable half of probe-ray splat culling (thesis 3.4) and of the
// hole-rate measurement, run by prt-cull's CPU path (preprocess/splat/cull_build.cpp, where the method is
// described) and its CUDA path (runtime/cuda/src/cull.cu) alike: PRT_HD, no STL, no allocation, no
// recursion. Probe directions come from a table the host computes once (no transcendental
// functions per probe), so the two backends shoot bit-identical probes when the CUDA code is
// compiled without FMA contraction (it is: --fmad=false).
#pragma once

#include <cstdint>

#include "prt/core/octree.h"
#include "prt/core/splat.h"
#include "prt/formats/pool_layout.h"

namespace prt::core {

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
    Vec3 d, u, v;
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
    OctreeView octree;                           ///< the replicated input octree
    const CullLeaf* leaves = nullptr;            ///< octree.filled_leaves entries, by leaf_info index
    const ProbeDirection* directions = nullptr;  ///< direction_sets x directions_per_set
    std::uint32_t direction_sets = 0;
    std::uint32_t directions_per_set = 0;
    std::uint32_t grid = 0;  ///< G: G x G probe lines per direction
    CullPolicy policy = CullPolicy::greedy;
    float window = 1.0f;     ///< blending window in radii of the nearest splat (RenderParams::blend_window)
    std::uint32_t seed = 0;  ///< jitter and direction-set choice
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

namespace cull_detail {

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

/// One pass over splats [begin, end): both sides' hits with t in [t0, t1] (intersect_splat,
/// the renderer's test, with the face each side expects).
PRT_HD PRT_INLINE void probe_hits(const OctreeView& v, std::uint32_t begin, std::uint32_t end,
                                  const std::uint8_t* keep, std::uint8_t kept_min, Vec3 o, Vec3 d, float t0,
                                  float t1, SideHits hits[2], CullCounters& c) {
    PRT_UNROLL
    for (int side = 0; side < 2; ++side) hits[side] = SideHits{k_inf, 0.0f, k_inf, false};
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = load_splat(v.splats + i);
        const bool side = dot(d, vec3(s.normal)) > 0.0f;
        float t, xr;
        ++c.splat_tests;
        if (!intersect_splat(s, o, d, side, t0, t1, t, xr)) continue;
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

/// The default `Hits` of cull_leaf(): probe_hits over the octree's splats, as the CUDA path runs it.
/// A backend may pass its own (the CPU path's reads a per-leaf structure-of-arrays copy, four
/// splats per step) as long as it gives the same SideHits: the backends must keep the same replicas.
struct OctreeProbeHits {
    PRT_HD PRT_INLINE void operator()(const OctreeView& v, std::uint32_t begin, std::uint32_t end,
                                      const std::uint8_t* keep, Vec3 o, Vec3 d, float t0, float t1,
                                      SideHits hits[2], CullCounters& c) const {
        probe_hits(v, begin, end, keep, k_keep_centre, o, d, t0, t1, hits, c);
    }
};

}  // namespace cull_detail

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
    Vec3 centre;   ///< the leaf box's centre; everything below is relative to it
    Vec3 lo, hi;   ///< the clipped box
    Vec3 n;        ///< slab normal (unit)
    float s0, s1;  ///< slab bounds along n
    float margin;
    std::uint32_t corner_count;  ///< vertices of P (at most 8 box corners + 24 edge/plane crossings)
    Vec3 corners[32];
};

/// Builds a leaf's ProbeRegion. Returns false when the leaf is unknown, has no splats or P is empty.
PRT_HD inline bool probe_region(const CullView& v, std::uint32_t leaf, ProbeRegion& r) {
    const CullLeaf L = v.leaves[leaf];
    if (L.level == k_cull_leaf_unknown) return false;
    std::uint32_t begin, end;
    leaf_splats(v.octree, L.node, begin, end);
    if (begin == end) return false;
    const float size = v.octree.root_size * exp2_neg(L.level);
    r.centre =
        v.octree.root_min + Vec3{static_cast<float>(L.cell[0]) + 0.5f, static_cast<float>(L.cell[1]) + 0.5f,
                                 static_cast<float>(L.cell[2]) + 0.5f} *
                                size;
    r.margin = size * (1.0f / 64.0f);
    Vec3 lo = vec3(k_inf), hi = vec3(-k_inf), nsum{0, 0, 0};
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = load_splat(v.octree.splats + i);
        const Vec3 n = vec3(s.normal), c = vec3(s.position) - r.centre;
        // a disk's extent along an axis a: r sqrt(1 - n_a^2)
        const Vec3 e{s.radius * sqrtf(fmaxf(0.0f, 1.0f - n.x * n.x)),
                     s.radius * sqrtf(fmaxf(0.0f, 1.0f - n.y * n.y)),
                     s.radius * sqrtf(fmaxf(0.0f, 1.0f - n.z * n.z))};
        lo = vmin(lo, c - e);
        hi = vmax(hi, c + e);
        nsum += n;
    }
    r.n = normalize_or(nsum, Vec3{0.0f, 0.0f, 1.0f});
    r.s0 = k_inf;
    r.s1 = -k_inf;
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat s = load_splat(v.octree.splats + i);
        const float cn = dot(r.n, vec3(s.normal));
        const float e = s.radius * sqrtf(fmaxf(0.0f, 1.0f - cn * cn));  // the disk's extent along n
        const float m = dot(r.n, vec3(s.position) - r.centre);
        r.s0 = fminf(r.s0, m - e);
        r.s1 = fmaxf(r.s1, m + e);
    }
    r.s0 -= r.margin;
    r.s1 += r.margin;
    const float half = 0.5f * size;
    r.lo = vmax(lo, vec3(-half)) - vec3(r.margin);
    r.hi = vmin(hi, vec3(half)) + vec3(r.margin);
    if (!(r.lo.x <= r.hi.x && r.lo.y <= r.hi.y && r.lo.z <= r.hi.z)) return false;
    // Vertices of P: box corners inside the slab, and where box edges cross the slab's planes.
    r.corner_count = 0;
    for (std::uint32_t c = 0; c < 8; ++c) {
        const Vec3 p{(c & 1u) ? r.hi.x : r.lo.x, (c & 2u) ? r.hi.y : r.lo.y, (c & 4u) ? r.hi.z : r.lo.z};
        const float m = dot(r.n, p);
        if (m >= r.s0 && m <= r.s1) r.corners[r.corner_count++] = p;
    }
    for (std::uint32_t axis = 0; axis < 3; ++axis) {
        for (std::uint32_t e = 0; e < 4; ++e) {  // the 4 box edges along `axis`
            const std::uint32_t b1 = (axis + 1) % 3, b2 = (axis + 2) % 3;
            float pa[3], pb[3];
            pa[axis] = component(r.lo, static_cast<int>(axis));
            pb[axis] = component(r.hi, static_cast<int>(axis));
            pa[b1] = pb[b1] = component((e & 1u) ? r.hi : r.lo, static_cast<int>(b1));
            pa[b2] = pb[b2] = component((e & 2u) ? r.hi : r.lo, static_cast<int>(b2));
            const Vec3 a{pa[0], pa[1], pa[2]}, b{pb[0], pb[1], pb[2]};
            const float ma = dot(r.n, a), mb = dot(r.n, b);
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

/// The hash that picks leaf `leaf`'s direction set and jitters its probes: of its level, its cell and
/// the seed, not of its index, so a leaf gets the same probes whichever part of the octree is culled
/// (the out-of-core build culls cell by cell, and its cells are built on several machines, issues 17
/// and 21).
PRT_HD inline std::uint32_t leaf_hash(const CullView& v, std::uint32_t leaf) {
    const CullLeaf& L = v.leaves[leaf];
    std::uint32_t h = cull_detail::hash32(L.level ^ cull_detail::hash32(v.seed));
    h = cull_detail::hash32(h ^ L.cell[0]);
    h = cull_detail::hash32(h ^ L.cell[1]);
    return cull_detail::hash32(h ^ L.cell[2]);
}

/// The frame of direction `di` (< directions_per_set) of leaf `leaf`: one of the 64 rotated
/// direction sets, picked by leaf_hash().
PRT_HD inline void probe_frame(const CullView& v, std::uint32_t leaf, const ProbeRegion& r, std::uint32_t di,
                               ProbeFrame& f) {
    f.dir = v.directions[(leaf_hash(v, leaf) % v.direction_sets) * v.directions_per_set + di];
    f.u0 = f.v0 = f.d0 = k_inf;
    f.u1 = f.v1 = f.d1 = -k_inf;
    for (std::uint32_t i = 0; i < r.corner_count; ++i) {
        const float pu = dot(f.dir.u, r.corners[i]), pv = dot(f.dir.v, r.corners[i]),
                    pd = dot(f.dir.d, r.corners[i]);
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
                              const ProbeFrame& f, std::uint32_t k, Vec3& o, Vec3& d, float& t_max) {
    const std::uint32_t cell = k % (v.grid * v.grid);
    const std::uint32_t gi = cell % v.grid, gj = cell / v.grid;
    const std::uint32_t h = cull_detail::hash32(leaf_hash(v, leaf) + k * 0x9e3779b9u);
    const float inv_g = 1.0f / static_cast<float>(v.grid);
    const float a = f.u0 + (f.u1 - f.u0) * ((static_cast<float>(gi) + cull_detail::unit_float(h)) * inv_g);
    const float b =
        f.v0 +
        (f.v1 - f.v0) * ((static_cast<float>(gj) + cull_detail::unit_float(cull_detail::hash32(h))) * inv_g);
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
        const float dc = dot(axis, d), oc = dot(axis, rel);
        const float l = ax == 3 ? r.s0 : component(r.lo, ax), u = ax == 3 ? r.s1 : component(r.hi, ax);
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

/// The probe's parameter range inside its leaf: the ray clipped to the leaf's closed cell, with the
/// renderer's arithmetic (walk_begin's normalized root coordinates, walk_step_out's cell planes c *
/// 2^-level). It depends on the leaf alone, not on the leaves the ray crosses before it, so a part of an
/// octree (an out-of-core brick build, issue 17) culls exactly as the whole tree does. Returns false when the
/// line misses the leaf's cell.
PRT_HD inline bool probe_leaf_range(const CullView& v, std::uint32_t leaf, Vec3 o, Vec3 d, float t_max,
                                    float& t0, float& t1) {
    const CullLeaf L = v.leaves[leaf];
    const Vec3 on = (o - v.octree.root_min) * v.octree.inv_root_size;
    const Vec3 dn = d * v.octree.inv_root_size;
    const float size = exp2_neg(L.level);
    float lo = 0.0f, hi = t_max;
    PRT_UNROLL
    for (int a = 0; a < 3; ++a) {
        const float oa = component(on, a), da = component(dn, a);
        const float c = static_cast<float>(L.cell[a]);
        const float r0 = c * size, r1 = (c + 1.0f) * size;  // exact: c < 2^24, size a power of 2
        if (da == 0.0f) {
            if (!(oa >= r0 && oa <= r1)) return false;
            continue;
        }
        const float ta = (r0 - oa) / da, tb = (r1 - oa) / da;
        lo = fmaxf(lo, fminf(ta, tb));
        hi = fminf(hi, fmaxf(ta, tb));
    }
    t0 = lo;
    t1 = hi;
    return t0 <= t1;
}

/// Probe line k of `leaf` (`frame` is set at the first line of each of its directions): the ray
/// o + t d, its range [t0, t1] inside the leaf, and both sides' nearest hits among the leaf's
/// centre splats [begin, end) (`probe_hits`, cull_detail::OctreeProbeHits or a backend's equal).
/// False when the line misses the leaf.
template <class Hits>
PRT_HD inline bool trace_probe_line(const CullView& v, std::uint32_t leaf, const ProbeRegion& region,
                                    ProbeFrame& frame, std::uint32_t k, std::uint32_t begin,
                                    std::uint32_t end, const std::uint8_t* keep, Vec3& o, Vec3& d, float& t0,
                                    float& t1, cull_detail::SideHits hits[2], CullCounters& c,
                                    Hits& probe_hits) {
    const std::uint32_t per_dir = v.grid * v.grid;
    float t_max;
    if (k % per_dir == 0) probe_frame(v, leaf, region, k / per_dir, frame);
    if (!make_probe(v, leaf, region, frame, k, o, d, t_max) ||
        !probe_leaf_range(v, leaf, o, d, t_max, t0, t1))
        return false;
    probe_hits(v.octree, begin, end, keep, o, d, t0, t1, hits, c);
    return true;
}

/// thesis 3.4: culls the replicas of filled leaf `leaf`. `keep` holds one flag per stored splat:
/// on entry k_keep_centre for the leaf's centre splats and k_keep_none for its replicas; on return
/// the replicas a probe needed are k_keep_probe. `votes` (one counter per stored splat, zero on
/// entry) is scratch for the votes policy and may be null otherwise. Only the leaf's own ranges of
/// `keep` and `votes` are touched, so leaves can be culled in parallel. `probe_hits` finds a probe
/// line's hits among the leaf's splats (see cull_detail::OctreeProbeHits).
///
/// Each probe line is two probe rays: o + t d and its reverse. A disk facing d is met by the
/// reverse ray only, so one pass over the splats serves both, and each leaf is probed from
/// 2 x directions directions without testing any line twice.
template <class Hits = cull_detail::OctreeProbeHits>
PRT_HD inline void cull_leaf(const CullView& v, std::uint32_t leaf, std::uint8_t* keep, std::uint32_t* votes,
                             CullCounters& c, Hits&& probe_hits = Hits{}) {
    const CullLeaf L = v.leaves[leaf];
    if (L.level == k_cull_leaf_unknown) return;
    std::uint32_t begin, end;
    leaf_splats(v.octree, L.node, begin, end);
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
    ProbeFrame frame{};
    const bool use_votes = v.policy == CullPolicy::votes && votes != nullptr;
    const pool::Splat* splats = v.octree.splats;
    // Votes pass: every probe ray the centre splats do not serve votes for each replica it hits
    // inside its blending window (thesis 3.4's per-splat counter).
    for (std::uint32_t k = 0; use_votes && k < lines; ++k) {
        Vec3 o, d;
        float t0, t1;
        cull_detail::SideHits hits[2];
        if (!trace_probe_line(v, leaf, region, frame, k, begin, end, keep, o, d, t0, t1, hits, c, probe_hits))
            continue;
        for (std::uint32_t side = 0; side < 2; ++side) {
            const cull_detail::SideHits& h = hits[side];
            if (!(h.near_s < k_inf)) continue;
            const float w_end = h.near_s + v.window * h.near_r;
            if (h.kept_s <= w_end) continue;
            float lo, hi;
            cull_detail::side_interval(side, h.near_s, w_end, t0, t1, lo, hi);
            for (std::uint32_t i = begin; i < end; ++i) {
                if (keep[i] != k_keep_none) continue;
                float t, xr;
                ++c.splat_tests;
                if (intersect_splat(load_splat(splats + i), o, d, side != 0, lo, hi, t, xr)) ++votes[i];
            }
        }
    }
    for (std::uint32_t k = 0; k < lines; ++k) {
        Vec3 o, d;
        float t0, t1;
        cull_detail::SideHits hits[2];
        if (!trace_probe_line(v, leaf, region, frame, k, begin, end, keep, o, d, t0, t1, hits, c, probe_hits))
            continue;
        c.probes += 2;
        for (std::uint32_t side = 0; side < 2; ++side) {
            const cull_detail::SideHits& h = hits[side];
            if (!(h.near_s < k_inf)) continue;
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
                    if (intersect_splat(load_splat(splats + i), o, d, side != 0, t0, t1, t, xr))
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
            cull_detail::side_interval(side, h.near_s, w_end, t0, t1, lo, hi);
            std::uint32_t best = end, best_votes = 0;
            float best_xr = 2.0f;
            for (std::uint32_t i = begin; i < end; ++i) {
                if (keep[i] != k_keep_none) continue;
                float t, xr;
                ++c.splat_tests;
                if (!intersect_splat(load_splat(splats + i), o, d, side != 0, lo, hi, t, xr)) continue;
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
    float t_full, t_culled;  ///< blended hit parameters (valid when hit)
    Vec3 n_full, n_culled;   ///< blended normals
    std::uint32_t hit_full, hit_culled;
};

PRT_HD inline void trace_hole_ray(const OctreeView& full, const OctreeView& culled, Vec3 o, Vec3 d,
                                  bool inside, const BlendOptions& blend, std::uint32_t max_steps,
                                  HoleSample& out) {
    WalkStats ws;
    SplatSample a{}, b{};
    out.hit_full = closest_hit_splats(full, nullptr, o, d, inside, k_inf, blend, max_steps, a, ws);
    out.hit_culled = closest_hit_splats(culled, nullptr, o, d, inside, k_inf, blend, max_steps, b, ws);
    out.t_full = a.t;
    out.t_culled = b.t;
    out.n_full = a.normal;
    out.n_culled = b.normal;
}

/// One ray of the hole measurement (preprocess/splat/cull_build.h makes them).
struct HoleRay {
    Vec3 o, d;             ///< model local frame, d unit
    std::uint32_t inside;  ///< 1: an inside ray (expects back faces)
};

}  // namespace prt::core
