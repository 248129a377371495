// PointRT core: ray tracing an Implicit Surface Octree (ISO, thesis ch. 4), host and device.
//
// An ISO (built by prt-iso, layout in prt/formats/iso_layout.h) is an octree whose filled leaves
// hold the implicit function f(Q) = (Q - p(Q)) . n(Q) of thesis 4.2 (eq. 4.1-4.3) at their 8
// corners, with weighted normals and colors. Inside a leaf, f, the normal and the color are
// trilinear interpolations of the corner values (thesis 4.3); the surface is f = 0, f > 0 outside
// (the side the point normals face), f <= 0 inside.
//
// Per ray, in the model's local frame (CPU loop or one CUDA thread per ray):
//     IsoHit hit; IsoStats stats;
//     if (trace_iso(view, o, d, t_max, inside, params, hit, stats)) ... hit.t, hit.normal, hit.color
//     bool shadowed = iso_occluded(view, o, d, t_max, inside, params, stats);
//     trace_iso(view, local_ray, t_max, hit)   // the same with default IsoParams
// Host setup: prt::rt::load_iso_view(pool) (prt/runtime/surface_pools.h) validates the sections.
//
// The walk (thesis 2.2) is the splat core's (prt/core/octree.h): the ISO's node words use the
// same encoding, so walk_begin/walk_next step through the leaves front to back with exact
// fixed-point stepping and no world-space epsilon. In each filled leaf (thesis 4.5):
//   1. the ray is sampled at regular intervals, `samples` per leaf edge of ray length, both ends
//      of the leaf's t range included; f at a sample is the trilinear interpolation of the 8
//      corner values at the sample's position in the leaf's unit cube;
//   2. the first sign change the ray accepts brackets the hit, and the hit is the weighted
//      interpolation of the two samples by their isovalues (the linear root, thesis 4.5);
//   3. optionally `refine_steps` regula falsi steps (Illinois variant, the bracket is kept) on
//      the same trilinear f: the accuracy knob (0 is the thesis's single interpolation);
//   4. the normal and color at the hit are trilinear interpolations of the corner normals and
//      colors; the normal is unit and agrees with the hit's face (below).
// thesis 4.5.1 (continuity): where a leaf meets a leaf one level finer, the two patches sample
// the surface at different rates and a thin seam opens between them. Each leaf's t range is
// widened by `seam_extension` leaf edges on both sides, so its trilinear patch is extrapolated
// slightly past its faces and covers the seam. A hit found in a widened range can be beaten by
// the next leaves, so the walk goes on until a leaf's widened range starts beyond the best hit.
// Seam stitching (an addition): the extrapolation closes thin seams only; where two filled leaves
// meet with f of different signs on their shared face (a level change, or quantization), a ray
// crossing that face from one to the other passes from + to - (or back) without either leaf
// seeing the change. The walk keeps the previous filled leaf's value at its exit; when the next
// filled leaf starts where it ended, or at most one leaf edge further on (a gap of empty cells
// the surface passes through but no leaf holds: rare, on noisy scans), and its entry value has
// the other sign, the ray has crossed the surface: the entry is the hit (normal and color from
// the entered leaf). A closed surface then has no holes; an open one (a scanned sheet) may gain a
// rim at most one leaf wide where a ray passes round its edge. Together with prt-iso's surface
// closure (every face a leaf's surface crosses has a filled leaf behind it) this measured 0
// holes on the analytic shapes and the scans tried (tests/preprocess/iso).
// thesis 4.5.2 (seamless ray tracing, 3.6): the hit point is approximate and may lie slightly
// on either side of f = 0, so a minimum hit distance would not do. A hit is a *front* face when
// f goes from + to - along the ray (the ray enters the object) and a back face when it goes from
// - to +. Outside rays (no k_ray_inside flag) accept only front faces, inside rays only back
// faces (IsoFaces::k_iso_faces_by_ray): a reflected ray leaves its surface towards f > 0 and a
// refracted one towards f < 0, so neither can meet the root it starts on. The returned normal is
// made to agree with the face (dot(normal, d) < 0 for front hits, > 0 for back hits): where the
// interpolated normal does not, the gradient of the trilinear f is used (counted in
// IsoStats::normal_fixes), so the renderer's facing-normal and refraction logic stays
// consistent with the flag.
//
// Everything is bounded: the walk by IsoParams::max_steps (IsoStats::truncated), the samples per
// leaf by k_iso_max_samples, refinement by refine_steps. No allocation, recursion or exceptions.
#pragma once

#include <cstdint>

#include "prt/core/config.h"
#include "prt/core/math.h"
#include "prt/core/octree.h"
#include "prt/core/ray.h"
#include "prt/formats/iso_layout.h"

namespace prt::core {

/// The ISO sections of one pool as the core reads them (built and validated on the host by
/// prt::rt::load_iso_view; the pointers may be device pointers to the same bytes).
struct IsoView {
    /// The node words and the root cube (walk_begin / walk_next read only nodes, node_count,
    /// root_min, root_size, inv_root_size; leaf_info and splats stay null).
    OctreeView tree;
    const pool::IsoLeafQ8* leaves_q8 = nullptr;    ///< leaf_count quantized leaves, or null
    const pool::IsoLeafF32* leaves_f32 = nullptr;  ///< leaf_count float leaves, or null
    std::uint32_t leaf_count = 0;
    std::uint32_t flags = 0;  ///< pool::IsoFlags (k_iso_colors: the colors mean something)
    /// Which array the tracer reads: the quantized one when set and present, else the float one.
    std::uint32_t use_q8 = 1;
};

/// The view over ISO arrays (a pool's sections, validated by pool::validate_iso, or a model in
/// memory): `q8` and `f32` null where absent; the tracer reads the quantized leaves when
/// `prefer_q8` and they are present, or when there are no float leaves. Host only.
inline IsoView make_iso_view(const pool::IsoInfo& info, const std::uint32_t* nodes, const pool::IsoLeafQ8* q8,
                             const pool::IsoLeafF32* f32, bool prefer_q8) {
    IsoView v;
    v.tree.nodes = nodes;
    v.tree.node_count = info.node_count;
    v.tree.filled_leaves = info.leaf_count;
    v.tree.root_min = Vec3{info.root_min[0], info.root_min[1], info.root_min[2]};
    v.tree.root_size = info.root_size;
    v.tree.inv_root_size = 1.0f / info.root_size;
    v.leaves_q8 = q8;
    v.leaves_f32 = f32;
    v.leaf_count = info.leaf_count;
    v.flags = info.flags;
    v.use_q8 = (prefer_q8 && q8 != nullptr) || f32 == nullptr ? 1u : 0u;
    return v;
}

/// Which sign changes of f count as hits.
enum IsoFaces : std::uint32_t {
    /// thesis 4.5.2 / 3.6: outside rays accept + to - (front faces), inside rays - to + (back).
    k_iso_faces_by_ray = 0,
    /// Any sign change: the first root along the ray whatever its direction.
    k_iso_faces_both = 1,
};

/// Intersection settings (thesis 4.5).
struct IsoParams {
    /// Sample intervals per leaf edge of ray length (a ray crossing a leaf's full diagonal gets
    /// sqrt(3) x samples intervals); at least 1 and at most k_iso_max_samples per leaf.
    float samples = 4.0f;
    /// Regula falsi (Illinois) steps after the weighted interpolation; 0 is the thesis's single
    /// interpolation. Each step is one more trilinear evaluation.
    std::uint32_t refine_steps = 2;
    /// thesis 4.5.1: each leaf's t range is widened by this many leaf edges on both sides
    /// (clamped to [0, 0.5]) to cover seams between leaves of different levels.
    float seam_extension = 0.05f;
    /// Seam stitching (an addition to the thesis, see the header comment): a sign change between
    /// the exit value of one filled leaf and the entry value of the next (adjacent, or at most one
    /// leaf edge further on) is a hit at that entry. 0 turns it off (the thesis's extrapolation
    /// alone).
    std::uint32_t stitch_seams = 1;
    std::uint32_t faces = k_iso_faces_by_ray;  ///< IsoFaces
    std::uint32_t max_steps = 1u << 16;        ///< leaves one ray may visit (a bound on every walk)
};

/// Most sample intervals in one leaf.
inline constexpr std::uint32_t k_iso_max_samples = 64;

/// Where a ray met the ISO surface.
struct IsoHit {
    float t = 0.0f;           ///< ray parameter (origin + t dir), in [0, t_max)
    Vec3 position{0, 0, 0};   ///< local frame
    Vec3 normal{0, 0, 1};     ///< unit, outward; agrees with `front` (see the header comment)
    Vec3 color{1, 1, 1};      ///< interpolated sRGB color in [0,1] (display-encoded); 1 without colors
    std::uint32_t front = 0;  ///< 1 when f went from + to - (the ray entered: a front face)
    std::uint32_t leaf = 0;   ///< index of the filled leaf holding the hit
    std::uint32_t level = 0;  ///< its level
};

/// Per-ray work counters (a backend sums them).
struct IsoStats {
    std::uint32_t leaves = 0;        ///< leaves visited (filled and empty)
    std::uint32_t filled = 0;        ///< filled leaves searched
    std::uint32_t evaluations = 0;   ///< trilinear evaluations of f
    std::uint32_t truncated = 0;     ///< 1 when max_steps ended the walk
    std::uint32_t normal_fixes = 0;  ///< hits whose interpolated normal disagreed with the face
};

namespace iso_detail {

/// 2^n as an exact float, 0 <= n <= 126.
PRT_HD PRT_INLINE float exp2_pos(std::uint32_t n) {
    return 1.0f / exp2_neg(n);  // exact: the reciprocal of a power of two
}

PRT_HD PRT_INLINE float lerp(float a, float b, float t) {
    return a + (b - a) * t;
}

/// Trilinear interpolation of 8 corner values (corner c = x | y << 1 | z << 2) at unit-cube
/// coordinates u (extrapolates linearly per axis outside [0,1]^3).
PRT_HD PRT_INLINE float trilinear(const float c[8], Vec3 u) {
    const float x00 = lerp(c[0], c[1], u.x), x10 = lerp(c[2], c[3], u.x);
    const float x01 = lerp(c[4], c[5], u.x), x11 = lerp(c[6], c[7], u.x);
    return lerp(lerp(x00, x10, u.y), lerp(x01, x11, u.y), u.z);
}

/// The 8 trilinear weights at u (sum 1), for interpolating vectors.
PRT_HD PRT_INLINE void trilinear_weights(Vec3 u, float w[8]) {
    const float x1 = u.x, x0 = 1.0f - u.x, y1 = u.y, y0 = 1.0f - u.y, z1 = u.z, z0 = 1.0f - u.z;
    w[0] = x0 * y0 * z0;
    w[1] = x1 * y0 * z0;
    w[2] = x0 * y1 * z0;
    w[3] = x1 * y1 * z0;
    w[4] = x0 * y0 * z1;
    w[5] = x1 * y0 * z1;
    w[6] = x0 * y1 * z1;
    w[7] = x1 * y1 * z1;
}

/// Gradient of the trilinear f with respect to u.
PRT_HD PRT_INLINE Vec3 trilinear_gradient(const float c[8], Vec3 u) {
    const float x00 = lerp(c[0], c[1], u.x), x10 = lerp(c[2], c[3], u.x);
    const float x01 = lerp(c[4], c[5], u.x), x11 = lerp(c[6], c[7], u.x);
    const float dx0 = lerp(c[1] - c[0], c[3] - c[2], u.y), dx1 = lerp(c[5] - c[4], c[7] - c[6], u.y);
    return Vec3{lerp(dx0, dx1, u.z), lerp(x10 - x00, x11 - x01, u.z),
                lerp(x01, x11, u.y) - lerp(x00, x10, u.y)};
}

}  // namespace iso_detail

/// The 8 corner isovalues of filled leaf `leaf` (one 8-byte read for quantized leaves, two
/// 16-byte reads for float ones, through the read-only cache on the GPU). Quantized values are
/// returned unscaled (value / 127 without the leaf's scale): the root search is scale-free.
PRT_HD PRT_INLINE void iso_leaf_values(const IsoView& v, std::uint32_t leaf, float out[8]) {
    if (v.use_q8 != 0 && v.leaves_q8 != nullptr) {
        const pool::IsoLeafQ8* p = v.leaves_q8 + leaf;
#if PRT_DEVICE_CODE
        const uint2 raw = __ldg(reinterpret_cast<const uint2*>(p));  // 56-byte leaves: 8-byte aligned
        const std::uint32_t words[2] = {raw.x, raw.y};
        PRT_UNROLL
        for (int c = 0; c < 8; ++c) {
            const std::int8_t q = static_cast<std::int8_t>((words[c >> 2] >> (8 * (c & 3))) & 0xffu);
            out[c] = static_cast<float>(q) * (1.0f / 127.0f);
        }
#else
        PRT_UNROLL
        for (int c = 0; c < 8; ++c) out[c] = static_cast<float>(p->value[c]) * (1.0f / 127.0f);
#endif
    } else {
        const pool::IsoLeafF32* p = v.leaves_f32 + leaf;
#if PRT_DEVICE_CODE
        const float4 a = __ldg(reinterpret_cast<const float4*>(p));  // 160-byte leaves: 16-byte aligned
        const float4 b = __ldg(reinterpret_cast<const float4*>(p) + 1);
        out[0] = a.x, out[1] = a.y, out[2] = a.z, out[3] = a.w;
        out[4] = b.x, out[5] = b.y, out[6] = b.z, out[7] = b.w;
#else
        PRT_UNROLL
        for (int c = 0; c < 8; ++c) out[c] = p->value[c];
#endif
    }
}

/// Scale of iso_leaf_values() of a leaf at `level` to local-frame units (f = value * scale).
PRT_HD PRT_INLINE float iso_value_scale(const IsoView& v, std::uint32_t level) {
    if (v.use_q8 != 0 && v.leaves_q8 != nullptr)
        return pool::k_iso_q8_range * v.tree.root_size * exp2_neg(level);
    return 1.0f;
}

/// Trilinear normal (unit, or zero when the corner normals cancel) and color of filled leaf
/// `leaf` at unit-cube coordinates u.
PRT_HD inline void iso_leaf_attributes(const IsoView& v, std::uint32_t leaf, Vec3 u, Vec3& normal,
                                       Vec3& color) {
    float w[8];
    iso_detail::trilinear_weights(u, w);
    Vec3 n{0, 0, 0}, c{0, 0, 0};
    if (v.use_q8 != 0 && v.leaves_q8 != nullptr) {
        const pool::IsoLeafQ8* p = v.leaves_q8 + leaf;
        PRT_UNROLL
        for (int k = 0; k < 8; ++k) {
            n += Vec3{float(p->normal[k][0]), float(p->normal[k][1]), float(p->normal[k][2])} * w[k];
            c += Vec3{float(p->color[k][0]), float(p->color[k][1]), float(p->color[k][2])} * w[k];
        }
    } else {
        const pool::IsoLeafF32* p = v.leaves_f32 + leaf;
        PRT_UNROLL
        for (int k = 0; k < 8; ++k) {
            n += Vec3{p->normal[k][0], p->normal[k][1], p->normal[k][2]} * w[k];
            c += Vec3{float(p->color[k].r), float(p->color[k].g), float(p->color[k].b)} * w[k];
        }
    }
    normal = normalize_or(n, Vec3{0, 0, 0});
    color = (v.flags & pool::k_iso_colors) != 0 ? clamp(c * (1.0f / 255.0f), 0.0f, 1.0f) : Vec3{1, 1, 1};
}

/// thesis 4.5: the first sign change of the trilinear f (corner values `c`) along the leaf-local
/// line u(t) = a + b t, t in [ta, tb], that a ray with flag `inside` accepts under `faces`;
/// `intervals` regular samples, then weighted interpolation and `refine` Illinois steps. On
/// success sets t_hit (in [ta, tb]) and front (f went from + to -).
PRT_HD inline bool iso_intersect_leaf(const float c[8], Vec3 a, Vec3 b, float ta, float tb,
                                      std::uint32_t intervals, std::uint32_t faces, bool inside,
                                      std::uint32_t refine, float& t_hit, bool& front,
                                      std::uint32_t& evaluations) {
    float t_prev = ta;
    float f_prev = iso_detail::trilinear(c, a + b * ta);
    ++evaluations;
    const float step = (tb - ta) / static_cast<float>(intervals);
    for (std::uint32_t k = 1; k <= intervals; ++k) {  // bounded: intervals <= k_iso_max_samples
        const float t = k == intervals ? tb : ta + step * static_cast<float>(k);
        const float f = iso_detail::trilinear(c, a + b * t);
        ++evaluations;
        const bool was_outside = f_prev > 0.0f;
        if (was_outside != (f > 0.0f) && (faces == k_iso_faces_both || was_outside != inside)) {
            // Bracket [lo, hi] with f_lo on the was_outside side; weighted interpolation (4.5).
            float lo = t_prev, hi = t, flo = f_prev, fhi = f;
            float tm = lo + (hi - lo) * (flo / (flo - fhi));
            int side = 0;
            for (std::uint32_t r = 0; r < refine; ++r) {  // Illinois regula falsi
                const float fm = iso_detail::trilinear(c, a + b * tm);
                ++evaluations;
                if ((fm > 0.0f) == was_outside) {
                    lo = tm, flo = fm;
                    if (side == -1) fhi *= 0.5f;
                    side = -1;
                } else {
                    hi = tm, fhi = fm;
                    if (side == 1) flo *= 0.5f;
                    side = 1;
                }
                const float den = flo - fhi;
                if (!(den != 0.0f) || !(hi > lo)) break;
                tm = lo + (hi - lo) * (flo / den);
            }
            t_hit = fminf(fmaxf(tm, t_prev), t);
            front = was_outside;
            return true;
        }
        t_prev = t;
        f_prev = f;
    }
    return false;
}

/// The walk behind trace_iso and iso_occluded: the nearest accepted hit with t in [0, t_max)
/// (`any`: the first one found, attributes not computed). Returns false on a miss. `k_regions`
/// false: walk_next without its macro-region code (the same hits, leaf by leaf).
template <bool k_regions = true>
PRT_HD inline bool iso_walk(const IsoView& v, Vec3 o, Vec3 d, float t_max, bool inside, const IsoParams& p,
                            bool any, IsoHit& hit, IsoStats& stats) {
    stats = IsoStats{};
    if (v.leaf_count == 0 || (v.leaves_q8 == nullptr && v.leaves_f32 == nullptr)) return false;
    if (!(dot(d, d) > 0.0f)) return false;
    OctreeWalk w;
    if (!walk_begin(v.tree, o, d, 0.0f, t_max, p.max_steps, w)) return false;
    const float dlen = length(w.d);  // normalized root units per unit of t
    if (!(dlen > 0.0f) || !is_finite(dlen)) return false;
    const float ext = clampf(p.seam_extension, 0.0f, 0.5f);
    const float samples = p.samples >= 1.0f / 64.0f ? p.samples : 1.0f / 64.0f;
    float best = t_max;
    bool found = false, best_front = false;
    std::uint32_t best_leaf = 0, best_level = 0;
    Vec3 best_a{0, 0, 0}, best_b{0, 0, 0};
    // Seam stitching: the previous filled leaf's exit t, its edge (root units) and whether f > 0
    // at its exit.
    float prev_t1 = -k_inf, prev_edge = 0.0f;
    bool prev_outside = false, prev_valid = false;
    OctreeLeaf leaf;
    while (walk_next<k_regions>(v.tree, w, leaf)) {  // bounded by max_steps
        ++stats.leaves;
        const float edge = exp2_neg(leaf.level);  // leaf edge in root units (exact)
        const float margin = ext * edge / dlen;   // 4.5.1 widening, in t
        if (found && leaf.t0 - margin >= best) break;
        if (!node_is_filled(leaf.node)) continue;
        const std::uint32_t index = node_addr(leaf.node);
        if (index >= v.leaf_count) {  // a validated view never gets here
            prev_valid = false;
            continue;
        }
        ++stats.filled;
        float c[8];
        iso_leaf_values(v, index, c);
        // Leaf-local unit-cube coordinates u(t) = a + b t: scaling by 2^level is exact.
        const float scale = iso_detail::exp2_pos(leaf.level);
        const Vec3 a = Vec3{w.o.x * scale - static_cast<float>(leaf.cell.x),
                            w.o.y * scale - static_cast<float>(leaf.cell.y),
                            w.o.z * scale - static_cast<float>(leaf.cell.z)};
        const Vec3 b = w.d * scale;
        // The closest hit so far becomes (t_hit, front_hit) in this leaf.
        const auto take = [&](float t_hit, bool front_hit) {
            best = t_hit;
            found = true;
            best_front = front_hit;
            best_leaf = index;
            best_level = leaf.level;
            best_a = a;
            best_b = b;
        };
        // Seam stitch: this leaf starts where the previous filled leaf ended, or within one edge,
        // with the other sign, and f of this leaf runs the same way along the ray (falling into
        // the object for + to -, rising out of it for - to +). The slope test rejects the seam
        // slivers a secondary ray meets right at its start, where two leaves disagree about the
        // side of a point on their face but neither surface is crossed the way the signs suggest.
        const bool contiguous =
            prev_valid && (leaf.t0 == prev_t1 || (leaf.t0 - prev_t1) * dlen <= fmaxf(prev_edge, edge));
        const Vec3 u0 = a + b * leaf.t0;
        const bool entry_outside = iso_detail::trilinear(c, u0) > 0.0f;
        ++stats.evaluations;
        if (p.stitch_seams != 0 && contiguous && prev_outside != entry_outside && leaf.t0 < best &&
            (p.faces == k_iso_faces_both || prev_outside != inside) &&
            (dot(iso_detail::trilinear_gradient(c, u0), b) < 0.0f) == prev_outside) {
            take(leaf.t0, prev_outside);
            if (any) break;
        }
        prev_valid = true;
        prev_t1 = leaf.t1;
        prev_edge = edge;
        prev_outside = iso_detail::trilinear(c, a + b * leaf.t1) > 0.0f;
        ++stats.evaluations;
        const float lo = fmaxf(leaf.t0 - margin, 0.0f);
        const float hi = fminf(leaf.t1 + margin, best);
        if (!(lo < hi)) continue;
        const float span = samples * (hi - lo) * dlen * scale;  // leaf edges crossed x samples
        std::uint32_t intervals = span < static_cast<float>(k_iso_max_samples)
                                      ? static_cast<std::uint32_t>(ceilf(span))
                                      : k_iso_max_samples;
        if (intervals < 1u) intervals = 1u;
        float t;
        bool front;
        if (iso_intersect_leaf(c, a, b, lo, hi, intervals, p.faces, inside, p.refine_steps, t, front,
                               stats.evaluations)) {
            if (t < best) {
                take(t, front);
                if (any) break;
            }
        }
    }
    stats.truncated = w.truncated ? 1u : 0u;
    if (!found) return false;
    hit.t = best;
    hit.front = best_front ? 1u : 0u;
    hit.leaf = best_leaf;
    hit.level = best_level;
    if (any) return true;
    hit.position = o + d * best;
    const Vec3 u = best_a + best_b * best;
    Vec3 n, color;
    iso_leaf_attributes(v, best_leaf, u, n, color);
    // thesis 4.5.2: the normal must agree with the face the sign change says was hit.
    const float dn = dot(n, d);
    if (!(best_front ? dn < 0.0f : dn > 0.0f)) {
        ++stats.normal_fixes;
        float c[8];
        iso_leaf_values(v, best_leaf, c);
        n = normalize_or(iso_detail::trilinear_gradient(c, u), Vec3{0, 0, 0});
        const float dg = dot(n, d);
        if (!(best_front ? dg < 0.0f : dg > 0.0f)) n = normalize(best_front ? -d : d);
    }
    hit.normal = n;
    hit.color = color;
    return true;
}

/// thesis 4.5: the nearest hit of the ray o + t d (model local frame; d need not be unit) with
/// the ISO surface, t in [0, t_max), accepting faces as `p.faces` says for a ray whose seamless
/// flag is `inside` (thesis 4.5.2). Returns false on a miss.
template <bool k_regions = true>
PRT_HD inline bool trace_iso(const IsoView& v, Vec3 o, Vec3 d, float t_max, bool inside, const IsoParams& p,
                             IsoHit& hit, IsoStats& stats) {
    return iso_walk<k_regions>(v, o, d, t_max, inside, p, false, hit, stats);
}

/// The same for a ray in the model's local frame with default IsoParams (its flag decides the
/// accepted faces; `t_max` replaces ray.t_max).
PRT_HD inline bool trace_iso(const IsoView& v, const Ray& ray, float t_max, IsoHit& hit) {
    IsoStats stats;
    return iso_walk(v, ray.origin, ray.dir, t_max, ray_inside(ray), IsoParams{}, false, hit, stats);
}

/// Whether the segment [0, t_max) of the ray meets the surface with a face the ray accepts
/// (shadow rays keep the flag of the ray they leave, so a surface never shadows itself).
template <bool k_regions = true>
PRT_HD inline bool iso_occluded(const IsoView& v, Vec3 o, Vec3 d, float t_max, bool inside,
                                const IsoParams& p, IsoStats& stats) {
    IsoHit hit;
    return iso_walk<k_regions>(v, o, d, t_max, inside, p, true, hit, stats);
}

/// f at a point of the local frame: the trilinear value in the filled leaf holding it, in
/// local-frame units (quantized leaves rescaled). Returns false outside the root or in an empty
/// leaf. For tests and tools.
PRT_HD inline bool iso_value_at(const IsoView& v, Vec3 p, float& f, std::uint32_t& level) {
    const Vec3 q = (p - v.tree.root_min) * v.tree.inv_root_size;
    if (!(q.x >= 0.0f && q.x <= 1.0f && q.y >= 0.0f && q.y <= 1.0f && q.z >= 0.0f && q.z <= 1.0f))
        return false;
    const Fixed3 fx{to_fixed(q.x), to_fixed(q.y), to_fixed(q.z)};
    const std::uint32_t node = find_leaf(v.tree, fx, level);
    if (!node_is_filled(node) || node_addr(node) >= v.leaf_count) return false;
    float c[8];
    iso_leaf_values(v, node_addr(node), c);
    const float scale = iso_detail::exp2_pos(level);
    const std::uint32_t shift = k_fixed_bits - level;
    const Vec3 u{q.x * scale - static_cast<float>(fx.x >> shift),
                 q.y * scale - static_cast<float>(fx.y >> shift),
                 q.z * scale - static_cast<float>(fx.z >> shift)};
    f = iso_detail::trilinear(c, u) * iso_value_scale(v, level);
    return true;
}

}  // namespace prt::core
