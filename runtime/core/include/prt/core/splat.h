// PointRT core: ray-splat intersection and weighted blending (thesis 3.3, 3.5, 3.6).
//
// A splat is an oriented disk (centre, normal, radius). A ray crossing an overlapping splat
// surface hits several disks; thesis 3.3 blends their hit positions, normals and colors with
// weights 1 - x_i/R_i (x_i: distance of the hit from disk i's centre, eq. 3.1).
//
// Which hits are blended: the nearest accepted hit fixes the surface; every accepted hit with
// t in [t_near, t_near + window * R_near / |d|] is blended (window = RenderParams::blend_window).
// Without deep blending only the leaf holding the nearest hit contributes (thesis 3.3); with deep
// blending (thesis 3.5) the walk goes on through the following leaves while they overlap the
// window, so splats of the same surface stored in the next leaf blend too. The thesis anchors
// that interval at the "reference splat" (the hit closest to its centre); this code anchors it
// at the nearest hit instead, so a second surface just behind the first can never win.
//
// Which hits are accepted: thesis 3.6 (seamless ray tracing): only faces of the kind the ray
// expects (front for outside rays, back for inside rays) and t in [0, t_max): no minimum-distance
// epsilon. In a replicated octree every disk is stored in every leaf it overlaps, so a leaf only
// accepts hits inside its own t range [t0, t1] and no replica is blended twice.
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/octree.h"
#include "prt/core/ray.h"
#include "prt/formats/pool_layout.h"

namespace prt::core {

/// Walk statistics a backend sums up (for benchmarks and the "never silent" rule).
struct WalkStats {
    std::uint32_t leaves = 0;  ///< leaves visited
    std::uint32_t splat_tests = 0;
    std::uint32_t truncated = 0;  ///< walks ended by the step bound
    std::uint32_t culled = 0;     ///< filled leaves passed by their LeafBounds, splats unread
    std::uint32_t fallbacks = 0;  ///< bricks met that were not resident: their LOD disc used (bricks.h)
};

/// Which LeafBounds tests may skip a filled leaf (RenderParams::leaf_culling).
enum LeafCulling : std::uint32_t {
    k_cull_none = 0,   ///< test every splat of every filled leaf
    k_cull_cones = 1,  ///< skip leaves whose normal cone holds no face the ray accepts
    k_cull_slabs = 2,  ///< also skip leaves whose slab the ray does not cross inside the leaf
};

/// Reads a splat (load_32_bytes: two 16-byte read-only loads on the GPU).
PRT_HD PRT_INLINE pool::Splat load_splat(const pool::Splat* p) {
    return load_32_bytes(p);
}

/// thesis 3.3: intersects the ray o + t d with one splat. On a hit with t in [t_lo, t_hi] (and the
/// expected face, thesis 3.6), returns true with t and x/R (distance from the centre over radius).
PRT_HD PRT_INLINE bool intersect_splat(const pool::Splat& s, Vec3 o, Vec3 d, bool inside, float t_lo,
                                       float t_hi, float& t, float& x_over_r) {
    const Vec3 n = vec3(s.normal);
    const float dn = dot(d, n);
    if (!face_expected(dn, inside)) return false;
    const Vec3 oc = o - vec3(s.position);
    const float th = -dot(oc, n) / dn;
    if (!(th >= t_lo && th <= t_hi)) return false;  // also rejects NaN
    const Vec3 pc = oc + d * th;                    // hit point relative to the centre
    const float x2 = length2(pc);
    const float r2 = s.radius * s.radius;
    if (!(x2 <= r2) || !(r2 > 0.0f)) return false;
    t = th;
    x_over_r = sqrtf(x2 / r2);
    return true;
}

/// Reads a leaf's bounds (load_32_bytes: two 16-byte read-only loads on the GPU).
PRT_HD PRT_INLINE LeafBounds load_leaf_bounds(const LeafBounds* p) {
    return load_32_bytes(p);
}

/// Whether a filled leaf can hold a hit the ray o + t d accepts with t in [t_lo, t_hi] (`inv_dlen`
/// = 1 / |d|). Conservative: false only when no splat of the leaf can give one, so skipping the
/// leaf changes no image.
///   cone (thesis 3.6: only the faces a ray expects are hits): an outside ray accepts a disk only
///     when dot(d, n) < 0. Over a cone of normals of half-angle theta about `axis`, the smallest
///     dot(d/|d|, n) is cos(phi + theta), phi the angle between d and the axis, which is >= 0 when
///     cos(phi) >= sin(theta). Then no normal faces the ray and the leaf is passed: this is what
///     makes secondary and shadow rays leave their own surface without reading its splats. Inside
///     rays accept dot(d, n) > 0: the same test with -axis.
///   slab: every hit point lies in the slab lo <= dot(axis, p) <= hi; the ray is inside the slab
///     only for t in one interval, which must meet [t_lo, t_hi].
PRT_HD PRT_INLINE bool bounds_may_hit(float ax, float ay, float az, float sin_theta, float blo, float bhi,
                                      Vec3 o, Vec3 d, float inv_dlen, bool inside, float t_lo, float t_hi,
                                      std::uint32_t mode) {
    const float sd = ax * d.x + ay * d.y + az * d.z;
    if ((inside ? -sd : sd) * inv_dlen >= sin_theta) return false;
    if (mode < k_cull_slabs) return true;
    const float so = ax * o.x + ay * o.y + az * o.z;
    // Rounding margin for the ray's side (the builder widened lo, hi for the splats' side): a few
    // hundred float ulps of the largest term, so a hit intersect_splat accepts is never lost.
    const float m = 1e-5f * (fabsf(so) + fabsf(blo) + fabsf(bhi));
    const float lo = blo - m, hi = bhi + m;
    if (!(lo <= hi)) return false;  // no splat of the leaf can be hit
    if (sd == 0.0f) return so >= lo && so <= hi;
#if PRT_DEVICE_CODE
    const float inv = 1.0f / sd;
    const float ta = (lo - so) * inv, tb = (hi - so) * inv;
    return fmaxf(ta, tb) >= t_lo && fminf(ta, tb) <= t_hi;
#else
    // The host compares in the slab's scale instead of dividing by sd (a division per leaf test):
    // the ray is in the slab for t between a / sd and b / sd (a = lo - so, b = hi - so), which meets
    // [t_lo, t_hi] iff b >= t_lo sd and a <= t_hi sd (sd > 0), or a <= t_lo sd and b >= t_hi sd
    // (sd < 0). t sd is rounded once, and where a comparison is close |t sd| is about |a| or |b|: an
    // error of a few ulps of |lo| + |so|, far inside the margin m. t_hi = inf gives +-inf and passes,
    // as the division did.
    const float a = lo - so, b = hi - so;
    if (sd > 0.0f) return b >= t_lo * sd && a <= t_hi * sd;
    return a <= t_lo * sd && b >= t_hi * sd;
#endif
}

PRT_HD PRT_INLINE bool leaf_may_hit(const LeafBounds& b, Vec3 o, Vec3 d, float inv_dlen, bool inside,
                                    float t_lo, float t_hi, std::uint32_t mode) {
    return bounds_may_hit(b.axis_x, b.axis_y, b.axis_z, b.sin_theta, b.lo, b.hi, o, d, inv_dlen, inside, t_lo,
                          t_hi, mode);
}

/// Reads a brick leaf's bounds: one 16-byte read-only load on the GPU (arena blocks are 64-byte
/// aligned).
PRT_HD PRT_INLINE BrickLeafBounds load_brick_leaf_bounds(const BrickLeafBounds* p) {
#if PRT_DEVICE_CODE
    const uint4 a = __ldg(reinterpret_cast<const uint4*>(p));
    BrickLeafBounds b;
    memcpy(&b, &a, sizeof(a));
    return b;
#else
    return *p;
#endif
}

/// leaf_may_hit for a brick leaf's compact bounds (octree.h, BrickLeafBounds): the same tests about
/// the integer axis, whose scale the threshold and the slab carry.
PRT_HD PRT_INLINE bool brick_leaf_may_hit(const BrickLeafBounds& b, Vec3 o, Vec3 d, float inv_dlen,
                                          bool inside, float t_lo, float t_hi, std::uint32_t mode) {
    return bounds_may_hit(float(b.axis_x), float(b.axis_y), float(b.axis_z), float(b.sin_code), b.lo, b.hi, o,
                          d, inv_dlen, inside, t_lo, t_hi, mode);
}

/// thesis 3.3, eq. 3.1: blending weight of a hit at x/R from its disk's centre. Floored at a
/// relative 1e-4 so hits exactly on rims still give a defined (not 0/0) blend.
PRT_HD PRT_INLINE float blend_weight(float x_over_r) {
    return fmaxf(1.0f - x_over_r, 1e-4f);
}

/// The blended surface sample of a closest-hit query, in the model's local frame.
struct SplatSample {
    float t;              ///< blended ray parameter (eq. 3.1 applied to positions on the ray)
    Vec3 normal;          ///< blended unit normal, as stored (outward)
    Vec3 color;           ///< blended point color in [0,1] (display-encoded, as stored); 1 without colors
    std::uint32_t point;  ///< source point of the nearest splat (material id lookup, thesis 3.3)
};

/// Blending options.
struct BlendOptions {
    float window = 1.0f;  ///< blending interval after the nearest hit, in units of its radius
    bool deep = false;    ///< thesis 3.5: blend across following leaves too
};

/// Where a leaf's splats come from (the template argument `Src` of the functions below): the float
/// splats of an octree view with the pool's per-point colors (OctreeSplats), or a brick's compressed
/// splats decoded on the fly (bricks.h). load(i) gives splat i as a pool::Splat whose `point` field
/// is what color() takes (and point_id(), which finish_nearest asks of the brick sources): the source
/// point index here, a packed colour in a brick; unit(n) gives a loaded normal as the unit vector
/// blending sums (a brick's splats load a normal that is not unit: bricks.h).
struct OctreeSplats {
    const pool::Splat* splats;
    const pool::Rgba8* colors;  ///< per point, or null (white)
    PRT_HD PRT_INLINE pool::Splat load(std::uint32_t i) const { return load_splat(splats + i); }
    /// A loaded normal as a unit vector, for blending: float splats' are unit already (a brick's
    /// are not, bricks.h).
    PRT_HD PRT_INLINE Vec3 unit(Vec3 n) const { return n; }
    /// The display-encoded colour in [0,1] of a splat's `point` field.
    PRT_HD PRT_INLINE Vec3 color(std::uint32_t point) const {
        if (colors == nullptr) return Vec3{1.0f, 1.0f, 1.0f};
        const pool::Rgba8 c = colors[point];
        constexpr float k = 1.0f / 255.0f;
        return Vec3{c.r * k, c.g * k, c.b * k};
    }
};

namespace detail {
struct BlendAccumulator {
    float w = 0.0f, wt = 0.0f;
    Vec3 wn{0, 0, 0};
    Vec3 wc{0, 0, 0};
};

template <class Src>
PRT_HD PRT_INLINE void blend_one(const Src& src, const pool::Splat& s, Vec3 o, Vec3 d, bool inside, float lo,
                                 float hi, BlendAccumulator& acc, WalkStats& stats) {
    float t, xr;
    PRT_COUNT(stats.splat_tests);
    if (!intersect_splat(s, o, d, inside, lo, hi, t, xr)) return;
    const float w = blend_weight(xr);
    acc.w += w;
    acc.wt += w * t;
    acc.wn += src.unit(vec3(s.normal)) * w;
    acc.wc += src.color(s.point) * w;
}

/// Blends the hits of splats [begin, end) with t in [lo, hi]; of the first 32 splats only those
/// whose bit is set in `mask` can hit (pass 1 found the others missing).
template <class Src>
PRT_HD PRT_INLINE void blend_leaf(const Src& src, std::uint32_t begin, std::uint32_t end, std::uint32_t mask,
                                  Vec3 o, Vec3 d, bool inside, float lo, float hi, BlendAccumulator& acc,
                                  WalkStats& stats) {
    const std::uint32_t n = end - begin;
    if (n < 32u) mask &= (1u << n) - 1u;
    while (mask != 0) {  // bounded: one bit cleared per iteration
        const std::uint32_t bit = count_trailing_zeros(mask);
        mask &= mask - 1u;
        blend_one(src, src.load(begin + bit), o, d, inside, lo, hi, acc, stats);
    }
    for (std::uint32_t i = begin + 32u; i < end; ++i) {
        blend_one(src, src.load(i), o, d, inside, lo, hi, acc, stats);
    }
}

/// The state of one closest-hit search (thesis 3.3): the nearest accepted hit so far, the blending
/// window it opened and the blend of the hits inside it.
struct NearestHit {
    bool found = false;
    float t_near = k_inf, window_end = k_inf;
    std::uint32_t near_point = 0;  ///< the nearest splat's `point` field (Src::color, Src::point_id)
    Vec3 near_normal{0, 0, 1};
    BlendAccumulator acc;
};

/// One leaf's splats [begin, end) with hits accepted in [lo, hi]. Pass 1 (first leaf with hits
/// only): the nearest accepted hit fixes the surface and the blending window; the hits of the
/// leaf's first 32 splats are remembered in a bit mask so pass 2 revisits only those (and every
/// splat past the 32nd). Pass 2: blend the accepted hits inside the window (thesis 3.3, eq. 3.1).
/// Returns whether the search is over (a hit found and no deep blending, thesis 3.5). The brick walk's
/// (bricks.h); closest_hit_splats writes the same passes out in its own loop, for speed.
template <class Src>
PRT_HD PRT_INLINE bool closest_in_leaf(const Src& src, std::uint32_t begin, std::uint32_t end, Vec3 o, Vec3 d,
                                       bool inside, float inv_dlen, float lo, float hi,
                                       const BlendOptions& blend, NearestHit& h, WalkStats& stats) {
    std::uint32_t mask = 0xffffffffu;
    if (!h.found) {
        mask = 0;
        for (std::uint32_t i = begin; i < end; ++i) {
            const pool::Splat s = src.load(i);
            float t, xr;
            PRT_COUNT(stats.splat_tests);
            if (!intersect_splat(s, o, d, inside, lo, hi, t, xr)) continue;
            if (i - begin < 32u) mask |= 1u << (i - begin);
            if (t < h.t_near || !h.found) {
                h.t_near = t;
                h.window_end = t + blend.window * s.radius * inv_dlen;
                h.near_point = s.point;
                h.near_normal = vec3(s.normal);
                h.found = true;
            }
        }
        if (!h.found) return false;
    }
    blend_leaf(src, begin, end, mask, o, d, inside, fmaxf(lo, h.t_near), fminf(hi, h.window_end), h.acc,
               stats);
    return !blend.deep;
}

/// Whether one of splats [begin, end) is hit with t in [lo, hi] (shadow rays).
template <class Src>
PRT_HD PRT_INLINE bool any_in_leaf(const Src& src, std::uint32_t begin, std::uint32_t end, Vec3 o, Vec3 d,
                                   bool inside, float lo, float hi, WalkStats& stats) {
    for (std::uint32_t i = begin; i < end; ++i) {
        float t, xr;
        PRT_COUNT(stats.splat_tests);
        if (intersect_splat(src.load(i), o, d, inside, lo, hi, t, xr)) return true;
    }
    return false;
}

/// The blended sample of a finished search; false when nothing was hit.
template <class Src>
PRT_HD PRT_INLINE bool finish_nearest(const Src& src, const NearestHit& h, SplatSample& out) {
    if (!h.found) return false;
    if (h.acc.w > 0.0f) {
        const float inv = 1.0f / h.acc.w;
        out.t = h.acc.wt * inv;
        out.normal = normalize_or(h.acc.wn, normalize(h.near_normal));
        out.color = h.acc.wc * inv;
    } else {
        out.t = h.t_near;
        out.normal = normalize(h.near_normal);
        out.color = src.color(h.near_point);
    }
    if (!(out.t >= h.t_near)) out.t = h.t_near;  // blended t never moves in front of the nearest hit
    out.point = src.point_id(h.near_point);
    return true;
}
}  // namespace detail

/// What the walk found for the caller (next_leaf).
enum class LeafStep : std::uint32_t {
    done,       ///< the walk ended, or the next leaf starts past `stop_after`
    skip,       ///< (unbatched walks only) a leaf with nothing to read: ask again
    candidate,  ///< a leaf whose splats must be read: [begin, end), accepted range [lo, hi]
};

/// The walk's next leaf whose splats must be read (thesis 2.2.1), passing empty leaves and, with
/// `bounds`, filled leaves whose LeafBounds rule out a hit in the range still searched: from the
/// leaf's t0 (`own_range`: replicated trees) or 0, to its t1 (`end_at_leaf`) or t_cap, at most
/// t_cap, clipped to [clip_lo, clip_hi]; that range before clipping is returned in [lo, hi]. The
/// walk stops at a leaf starting past `stop_after`.
///
/// k_batched (PRT_BATCHED_WALK): keep stepping until such a leaf is found ("while-while", Aila and
/// Laine 2009) instead of returning `skip` after every step that finds nothing to read ("if-if",
/// the default: measured faster here, runtime/README.md).
template <bool k_batched>
PRT_HD PRT_INLINE LeafStep next_leaf(const OctreeView& v, OctreeWalk& walk, OctreeLeaf& leaf,
                                     const LeafBounds* bounds, std::uint32_t culling, Vec3 o, Vec3 d,
                                     float inv_dlen, bool inside, bool own_range, bool end_at_leaf,
                                     float t_cap, float clip_lo, float clip_hi, float stop_after,
                                     std::uint32_t& begin, std::uint32_t& end, float& lo, float& hi,
                                     WalkStats& stats) {
    while (walk_next(v, walk, leaf)) {  // bounded by max_steps
        PRT_COUNT(stats.leaves);
        if (leaf.t0 > stop_after) return LeafStep::done;
        lo = own_range ? leaf.t0 : 0.0f;
        hi = end_at_leaf ? fminf(leaf.t1, t_cap) : t_cap;
        if (bounds != nullptr) {
            // One read gives the splat range and the bounds; a leaf whose bounds rule out every
            // hit in the range still searched is passed without reading its splats.
            if (!node_is_filled(leaf.node) || node_addr(leaf.node) >= v.filled_leaves) {
                if (k_batched) continue;
                return LeafStep::skip;
            }
            const LeafBounds b = load_leaf_bounds(bounds + node_addr(leaf.node));
            begin = b.begin;
            end = b.end;
            if (begin >= end) {
                if (k_batched) continue;
                return LeafStep::skip;
            }
            if (!leaf_may_hit(b, o, d, inv_dlen, inside, fmaxf(lo, clip_lo), fminf(hi, clip_hi), culling)) {
                PRT_COUNT(stats.culled);
                if (k_batched) continue;
                return LeafStep::skip;
            }
        } else {
            leaf_splats(v, leaf.node, begin, end);
            if (begin == end) {
                if (k_batched) continue;
                return LeafStep::skip;
            }
        }
        return LeafStep::candidate;
    }
    return LeafStep::done;
}

/// Closest hit of a ray with a model's splats (model local frame; d need not be unit). Hits are
/// searched in t in [0, t_max). `colors` may be null. Returns false on a miss. `culling`
/// (LeafCulling) says which of the view's LeafBounds tests may skip a filled leaf.
/// The walk and both passes are written out in one loop, with local state, rather than calling the
/// brick walk's closest_in_leaf (the same passes over a NearestHit): on an H100 the CUDA splat kernel
/// ran the shared form at 0.78 / 1.28 / 0.47 / 0.66 Grays/s (prt-bench room: primary, shadow,
/// reflect4, full4) and this one at 0.96 / 1.52 / 0.55 / 0.91, with the same rays, leaves and splat
/// tests and the same image: the shared form executed 19 % more warp instructions for the same
/// thread instructions (ncu; preprocess/bench/results/h100-2026-11-26-issue19-loop). Keep the two in step.
PRT_HD inline bool closest_hit_splats(const OctreeView& v, const pool::Rgba8* colors, Vec3 o, Vec3 d,
                                      bool inside, float t_max, const BlendOptions& blend,
                                      std::uint32_t max_steps, SplatSample& out, WalkStats& stats,
                                      std::uint32_t culling = k_cull_slabs) {
    OctreeWalk walk;
    if (!walk_begin(v, o, d, 0.0f, t_max, max_steps, walk)) return false;
    const bool replicated = (v.flags & pool::k_octree_replicated) != 0;
    const float inv_dlen = 1.0f / length(d);
    const LeafBounds* bounds = culling != k_cull_none ? v.leaf_bounds : nullptr;
    bool found = false;
    float t_near = k_inf, window_end = k_inf;
    std::uint32_t near_point = 0;
    Vec3 near_normal{0, 0, 1};
    detail::BlendAccumulator acc;
    OctreeLeaf leaf;
    for (;;) {  // bounded: every pass takes at least one walk step, and walks are bounded
        // The next leaf with splats to read, and the t range [lo, hi] its hits are accepted in: a
        // replicated tree holds every disk in every leaf it overlaps, so only this leaf's t range
        // (own_range); a tree without replicas keeps each disk in one leaf only: from t = 0.
        std::uint32_t begin = 0, end = 0;
        float lo = 0.0f, hi = 0.0f;
        const LeafStep step = next_leaf<PRT_BATCHED_WALK != 0>(
            v, walk, leaf, bounds, culling, o, d, inv_dlen, inside, replicated, true, t_max,
            found ? t_near : 0.0f, found ? window_end : k_inf, found ? window_end : k_inf, begin, end, lo, hi,
            stats);
        if (step == LeafStep::done) break;
        if (step == LeafStep::skip) continue;
        // Pass 1 (first leaf with hits only): the nearest accepted hit fixes the surface and the
        // blending window; the hits of the leaf's first 32 splats are remembered in a bit mask so
        // pass 2 revisits only those (and every splat past the 32nd).
        std::uint32_t mask = 0xffffffffu;
        if (!found) {
            mask = 0;
            for (std::uint32_t i = begin; i < end; ++i) {
                const pool::Splat s = load_splat(v.splats + i);
                float t, xr;
                PRT_COUNT(stats.splat_tests);
                if (!intersect_splat(s, o, d, inside, lo, hi, t, xr)) continue;
                if (i - begin < 32u) mask |= 1u << (i - begin);
#if !PRT_DEVICE_CODE
                // Pass 2 blends this splat's colour, a read by source point (a cache miss on the
                // host, where it was ~3 % of a shadow frame): start it now.
                if (colors != nullptr) __builtin_prefetch(colors + s.point);
#endif
                if (t < t_near || !found) {
                    t_near = t;
                    window_end = t + blend.window * s.radius * inv_dlen;
                    near_point = s.point;
                    near_normal = vec3(s.normal);
                    found = true;
                }
            }
            if (!found) continue;
        }
        // Pass 2: blend the accepted hits inside the window (thesis 3.3, eq. 3.1).
        detail::blend_leaf(OctreeSplats{v.splats, colors}, begin, end, mask, o, d, inside, fmaxf(lo, t_near),
                           fminf(hi, window_end), acc, stats);
        if (!blend.deep) break;
    }
    if (walk.truncated) ++stats.truncated;
    if (!found) return false;
    if (acc.w > 0.0f) {
        const float inv = 1.0f / acc.w;
        out.t = acc.wt * inv;
        out.normal = normalize_or(acc.wn, normalize(near_normal));
        out.color = acc.wc * inv;
    } else {
        out.t = t_near;
        out.normal = normalize(near_normal);
        out.color = OctreeSplats{v.splats, colors}.color(near_point);
    }
    if (!(out.t >= t_near)) out.t = t_near;  // blended t never moves in front of the nearest hit
    out.point = near_point;
    return true;
}

/// Any hit of a ray with a model's splats in t in [0, t_max) (shadow rays, thesis 5.2). `culling`
/// as for closest_hit_splats.
/// Written out like closest_hit_splats (any_in_leaf is the brick walk's): over the closest-hit change
/// alone, this took the room's shadow frames from 1.44 to 1.48 Grays/s and full4 from 0.76 to 0.90.
PRT_HD inline bool any_hit_splats(const OctreeView& v, Vec3 o, Vec3 d, bool inside, float t_max,
                                  std::uint32_t max_steps, WalkStats& stats,
                                  std::uint32_t culling = k_cull_slabs) {
    OctreeWalk walk;
    if (!walk_begin(v, o, d, 0.0f, t_max, max_steps, walk)) return false;
    OctreeLeaf leaf;
    // An occluder anywhere on [0, t_max) counts, whichever leaf finds it.
    const float hi = next_toward_zero(t_max);
    const LeafBounds* bounds = culling != k_cull_none ? v.leaf_bounds : nullptr;
    const float inv_dlen = bounds != nullptr ? 1.0f / length(d) : 0.0f;
    // In a fully replicated tree every hit also lies in the leaf holding the hit point, which the
    // walk visits: a leaf may be passed when its bounds rule out hits inside its own t range.
    // Culled trees (prt-cull) lack some replicas, so there the whole [0, t_max) range is kept.
    const bool own_range =
        (v.flags & pool::k_octree_replicated) != 0 && (v.flags & pool::k_octree_culled) == 0;
    for (;;) {  // bounded: every pass takes at least one walk step, and walks are bounded
        std::uint32_t begin = 0, end = 0;
        float leaf_lo, leaf_hi;
        const LeafStep step = next_leaf<PRT_BATCHED_WALK != 0>(v, walk, leaf, bounds, culling, o, d, inv_dlen,
                                                               inside, own_range, own_range, hi, 0.0f, k_inf,
                                                               k_inf, begin, end, leaf_lo, leaf_hi, stats);
        if (step == LeafStep::done) break;
        if (step == LeafStep::skip) continue;
        for (std::uint32_t i = begin; i < end; ++i) {
            float t, xr;
            PRT_COUNT(stats.splat_tests);
            if (intersect_splat(load_splat(v.splats + i), o, d, inside, 0.0f, hi, t, xr)) return true;
        }
    }
    if (walk.truncated) ++stats.truncated;
    return false;
}

}  // namespace prt::core
