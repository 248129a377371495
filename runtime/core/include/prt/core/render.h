// PointRT core: one ray tracer for every backend. Closest hits over all models, local shading
// with shadow rays, reflection and refraction with per-ray intensity and a bounce limit, all
// iterative (thesis 2: no recursion on the GPU) with a fixed-size ray stack.
//
// Backends call render_pixel() (one thread per pixel: the CPU backend and the CUDA megakernel), or
// the three stages closest_hit_scene() / shade_hit() / spawn_secondary() separately (the CUDA
// wavefront kernels of thesis 2.4).
#pragma once

#include <cstdint>
#include <type_traits>

#include "prt/core/camera.h"
#include "prt/core/iso.h"
#include "prt/core/math.h"
#include "prt/core/mls.h"
#include "prt/core/patch.h"
#include "prt/core/ray.h"
#include "prt/core/scene_view.h"
#include "prt/core/shading.h"
#include "prt/core/splat.h"

namespace prt::core {

/// Per-thread ray and work counters; backends sum them per frame (64-bit on the host).
struct RayCounters {
    std::uint32_t primary = 0;
    std::uint32_t secondary = 0;  ///< reflection and refraction rays
    std::uint32_t shadow = 0;
    std::uint32_t leaves = 0;  ///< octree leaves visited (all ray kinds)
    std::uint32_t splat_tests = 0;
    std::uint32_t truncated = 0;  ///< walks cut by RenderParams::max_steps
    std::uint32_t sanitized = 0;  ///< non-finite pixels replaced by black
    std::uint32_t dropped = 0;    ///< secondary rays dropped because the ray stack was full
    std::uint32_t culled = 0;     ///< filled leaves passed by their LeafBounds (splat.h)
    /// Rays that met a non-resident brick and used its LOD disc (bricks.h; counted once per ray and
    /// bricked model, however many bricks it fell back on)
    std::uint32_t fallbacks = 0;
};

/// Adds the ray counters of b to a: RayCounters, or any type with the same fields (the host's
/// rt::FrameStats sums them per frame).
template <class A, class B>
PRT_HD PRT_INLINE void add_ray_counters(A& a, const B& b) {
    a.primary += b.primary;
    a.secondary += b.secondary;
    a.shadow += b.shadow;
    a.leaves += b.leaves;
    a.splat_tests += b.splat_tests;
    a.truncated += b.truncated;
    a.sanitized += b.sanitized;
    a.dropped += b.dropped;
    a.culled += b.culled;
    a.fallbacks += b.fallbacks;
}

PRT_HD PRT_INLINE RayCounters& operator+=(RayCounters& a, const RayCounters& b) {
    add_ray_counters(a, b);
    return a;
}

/// Adds one surface's work to the ray counters (leaves: octree leaves / ISO leaves / kd-tree cells /
/// BVH nodes visited; splat_tests: splat tests / evaluations of f or F / Newton steps).
PRT_HD PRT_INLINE void add_work(RayCounters& c, std::uint32_t leaves, std::uint32_t tests,
                                std::uint32_t truncated, std::uint32_t culled) {
    c.leaves += leaves;
    c.splat_tests += tests;
    c.truncated += truncated;
    c.culled += culled;
}
PRT_HD PRT_INLINE void add_stats(RayCounters& c, const WalkStats& w) {
    add_work(c, w.leaves, w.splat_tests, w.truncated, w.culled);
    c.fallbacks += w.fallbacks != 0 ? 1u : 0u;  // rays, not brick visits
}
PRT_HD PRT_INLINE void add_stats(RayCounters& c, const IsoStats& st) {
    add_work(c, st.leaves, st.evaluations, st.truncated, 0);
}
PRT_HD PRT_INLINE void add_stats(RayCounters& c, const MlsStats& st) {
    add_work(c, st.cells, st.evaluations, st.truncated, 0);
}
PRT_HD PRT_INLINE void add_stats(RayCounters& c, const PatchStats& st) {
    add_work(c, st.bvh_nodes, st.newton_iterations, 0, 0);
}

/// A shaded surface point in the render frame.
struct SurfaceHit {
    float t;
    Vec3 position;
    Vec3 normal;      ///< unit, outward (as stored); the ray's flag says which face was hit
    Vec3 base_color;  ///< linear; (1,1,1) when the material ignores point colors
    std::uint32_t material;
    std::uint32_t model = 0;   ///< index into SceneView::models
    std::uint32_t prim = 0;    ///< patch index (patches), else 0
    float u = 0.0f, v = 0.0f;  ///< patch parameters (patches), else 0
};

/// The ray in a model's local frame (t is unchanged: d is scaled, not normalized).
PRT_HD PRT_INLINE void to_model_frame(const ModelView& m, const Ray& r, Vec3& o, Vec3& d) {
    o = mul_transpose(m.rotation, r.origin - m.offset) * m.inv_scale;
    d = mul_transpose(m.rotation, r.dir) * m.inv_scale;
}

/// The nearest hit on one model, in its local frame, whatever its surface.
struct ModelHit {
    float t = 0.0f;
    Vec3 normal{0, 0, 1};               ///< local frame, unit, outward
    Vec3 color{1, 1, 1};                ///< display-encoded (sRGB) point color; 1 without colors
    std::uint32_t point = 0xffffffffu;  ///< source point (per-point material ids), or none
    std::uint32_t prim = 0;
    float u = 0.0f, v = 0.0f;
};

/// ISO and MLS settings for the renderer's rays: the scene's knobs with the seamless face rule
/// (thesis 3.6 / 4.5.2: f's sign change tells front from back).
PRT_HD PRT_INLINE IsoParams iso_params_for(const SceneView& s) {
    IsoParams p = s.params.iso;
    p.faces = k_iso_faces_by_ray;
    return p;
}
PRT_HD PRT_INLINE MlsParams mls_params_for(const SceneView& s) {
    MlsParams p = s.params.mls;
    p.faces = k_mls_faces_by_ray;
    return p;
}

/// Patch settings for a ray: the seamless rule (thesis 3.6) on oriented pools; on unoriented ones
/// both faces count and a ray leaving a patch of this model skips its own start point.
PRT_HD PRT_INLINE PatchTraceParams patch_params_for(const SceneView& s, const ModelView& mv, std::uint32_t m,
                                                    const Ray& r) {
    PatchTraceParams p = s.params.patch;
    if ((mv.patches.flags & pool::k_patch_oriented) != 0) {
        p.faces = k_patch_faces_by_ray;
    } else {
        p.faces = k_patch_faces_both;
        if (r.from_model == m) {
            p.skip_patch = r.from_prim;
            p.skip_u = r.from_u;
            p.skip_v = r.from_v;
        }
    }
    return p;
}

/// Which code a kernel carries (a template argument of the functions below): the surfaces it can
/// meet (bit 1 << SurfaceKind) and whether it samples pixels (path.h). The CUDA backend launches
/// the smallest kernel a scene needs, so a splat scene keeps the registers (and the speed) of a
/// splat-only kernel; the CPU backend uses k_mask_all.
enum KernelMask : std::uint32_t {
    k_mask_splats = 1u << static_cast<std::uint32_t>(SurfaceKind::splats),
    k_mask_iso = 1u << static_cast<std::uint32_t>(SurfaceKind::iso),
    k_mask_mls = 1u << static_cast<std::uint32_t>(SurfaceKind::mls),
    k_mask_patches = 1u << static_cast<std::uint32_t>(SurfaceKind::patches),
    k_mask_sampling = 1u << scene::k_surface_kind_count,  ///< spp > 1 or path tracing
    /// Splats of bricked pools (bricks.h; issue 17): their own bit, so a kernel for float splats
    /// does not carry the brick walk's registers.
    k_mask_bricks = k_mask_sampling << 1,
    /// Reflected and refracted rays (trace_ray): a kernel without this bit traces the primary ray
    /// and its shadow rays only, with no stack of pending rays (for frames that spawn none:
    /// spawns_secondary()).
    k_mask_secondary = k_mask_bricks << 1,
    k_mask_all = (k_mask_secondary << 1) - 1,
    /// ISO kernels without secondary rays for frames that trace shadow rays: closest hits and
    /// shadow rays share one walk loop (trace_ray_shared), as ISO kernels with secondary rays
    /// always do. Not in k_mask_all: it picks a code shape, not code a scene needs.
    k_mask_shadow_walk = k_mask_secondary << 1,
    /// ISO kernels whose walk has no macro-region code (walk_next<false>): leaf by leaf, the regions
    /// unread. Where a scene's regions save few steps (a dense model seen from outside: most empty
    /// leaves small), the walk without their loads and clamps is the faster one; the CUDA backend
    /// times both (cuda_backend.cu, WalkChoice). Not in k_mask_all: a code shape, as above.
    k_mask_plain_walk = k_mask_shadow_walk << 1,
};

/// Which materials of a scene could spawn secondary rays (spawn_secondary): the frame's parameters
/// decide whether they do (spawns_secondary).
struct SecondaryMaterials {
    bool reflective = false;    ///< some material's reflectivity is above 0
    bool transmissive = false;  ///< some material's transmissivity is above 0
};

inline SecondaryMaterials secondary_materials(const Material* materials, std::uint32_t count) {
    SecondaryMaterials m;
    for (std::uint32_t i = 0; i < count; ++i) {
        m.reflective = m.reflective || materials[i].reflectivity > 0.0f;
        m.transmissive = m.transmissive || materials[i].transmissivity > 0.0f;
    }
    return m;
}

/// Whether a frame can spawn a reflected or refracted ray: spawn_secondary() returns none when the
/// bounce limit is 0 or no material reflects (refracts) with reflections (refractions) on. Frames
/// that cannot run kernels without k_mask_secondary; their images are the same.
inline bool spawns_secondary(const RenderParams& p, SecondaryMaterials m) {
    return p.max_bounces > 0 && ((p.reflections != 0 && m.reflective) || (p.refractions != 0 && m.transmissive));
}

/// Whether some light of a scene casts shadows: frames with shadows on then trace shadow rays
/// (shade_hit), which k_mask_shadow_walk kernels serve.
inline bool casts_any_shadow(const PointLight* lights, std::uint32_t count) {
    for (std::uint32_t i = 0; i < count; ++i)
        if (lights[i].casts_shadows != 0) return true;
    return false;
}

/// The mask a scene needs (k_mask_secondary aside: that bit depends on the frame, spawns_secondary).
PRT_HD inline std::uint32_t scene_mask(const SceneView& s) {
    std::uint32_t m = (s.params.spp > 1 || s.params.path_tracing != 0) ? k_mask_sampling : 0u;
    for (std::uint32_t i = 0; i < s.model_count; ++i) {
        // a bricked model needs the brick walk only, not the float splat code (dispatch_surface)
        if (s.models[i].surface == SurfaceKind::splats && s.models[i].bricks.top_nodes != nullptr)
            m |= k_mask_bricks;
        else
            m |= 1u << static_cast<std::uint32_t>(s.models[i].surface);
    }
    return m;
}

/// A surface kind as a type: what dispatch_surface() hands on, so each surface's code is its own
/// overload below and a kernel compiles only the overloads its KernelMask names.
template <SurfaceKind S>
struct SurfaceTag {
    static constexpr SurfaceKind kind = S;
};
/// ISO, walked with its macro-regions (`k_regions`) or without (k_mask_plain_walk kernels).
template <bool k_regions>
struct IsoTag {
    static constexpr SurfaceKind kind = SurfaceKind::iso;
};
/// Splats of a bricked pool (ModelView::bricks set): a surface of its own for the dispatch.
struct BricksTag {
    static constexpr SurfaceKind kind = SurfaceKind::splats;
};

/// Ray r in model `model`'s local frame (to_model_frame), as every surface query takes it.
struct ModelRay {
    const ModelView& mv;
    std::uint32_t model;
    const Ray& ray;  ///< render frame (t is the same in both frames)
    Vec3 o, d;
    bool inside;
};

// ---- One surface each: the closest hit in [0, t_max) and whether anything blocks [0, t_max) ----
// Splats (thesis 3.3 blending), ISO (thesis 4.5), MLS (WS05 3.2), patches (seed 002, 3). Every
// surface takes the seamless flag (thesis 3.6) instead of an epsilon.

template <bool k_regions>
PRT_HD PRT_INLINE bool closest_on(IsoTag<k_regions>, const SceneView& s, const ModelRay& q, float t_max,
                                  ModelHit& out, RayCounters& c) {
    IsoHit h;
    IsoStats st;
    const bool hit = trace_iso<k_regions>(q.mv.iso, q.o, q.d, t_max, q.inside, iso_params_for(s), h, st);
    add_stats(c, st);
    if (hit)
        out = ModelHit{h.t, h.normal, (q.mv.iso.flags & pool::k_iso_colors) != 0 ? h.color : Vec3{1, 1, 1}};
    return hit;
}
template <bool k_regions>
PRT_HD PRT_INLINE bool occluded_on(IsoTag<k_regions>, const SceneView& s, const ModelRay& q, RayCounters& c) {
    IsoStats st;
    const bool hit =
        iso_occluded<k_regions>(q.mv.iso, q.o, q.d, q.ray.t_max, q.inside, iso_params_for(s), st);
    add_stats(c, st);
    return hit;
}

PRT_HD PRT_INLINE bool closest_on(SurfaceTag<SurfaceKind::mls>, const SceneView& s, const ModelRay& q,
                                  float t_max, ModelHit& out, RayCounters& c) {
    MlsHit h;
    MlsStats st;
    const bool hit = trace_mls<float>(q.mv.mls, q.o, q.d, t_max, q.inside, mls_params_for(s), h, st);
    add_stats(c, st);
    if (hit) out = ModelHit{h.t, h.normal, mls_blend_color(q.mv.mls, q.mv.colors, h), h.point};
    return hit;
}
PRT_HD PRT_INLINE bool occluded_on(SurfaceTag<SurfaceKind::mls>, const SceneView& s, const ModelRay& q,
                                   RayCounters& c) {
    MlsStats st;
    const bool hit = mls_occluded<float>(q.mv.mls, q.o, q.d, q.ray.t_max, q.inside, mls_params_for(s), st);
    add_stats(c, st);
    return hit;
}

PRT_HD PRT_INLINE bool closest_on(SurfaceTag<SurfaceKind::patches>, const SceneView& s, const ModelRay& q,
                                  float t_max, ModelHit& out, RayCounters& c) {
    const PatchTraceParams p = patch_params_for(s, q.mv, q.model, q.ray);
    PatchHit h;
    PatchStats st;
    const bool hit = trace_patches(q.mv.patches, make_patch_ray(q.o, q.d, t_max, q.inside), p, h, &st);
    add_stats(c, st);
    if (!hit || !(h.t < static_cast<double>(t_max))) return false;
    out.t = static_cast<float>(h.t);
    out.normal =
        Vec3{static_cast<float>(h.normal.x), static_cast<float>(h.normal.y), static_cast<float>(h.normal.z)};
    out.color = Vec3{1, 1, 1};
    out.point = 0xffffffffu;
    out.prim = h.patch;
    out.u = static_cast<float>(h.u);
    out.v = static_cast<float>(h.v);
    return true;
}
PRT_HD PRT_INLINE bool occluded_on(SurfaceTag<SurfaceKind::patches>, const SceneView& s, const ModelRay& q,
                                   RayCounters& c) {
    const PatchTraceParams p = patch_params_for(s, q.mv, q.model, q.ray);
    PatchStats st;
    const bool hit = patches_occluded(q.mv.patches, make_patch_ray(q.o, q.d, q.ray.t_max, q.inside), p, &st);
    add_stats(c, st);
    return hit;
}

PRT_HD PRT_INLINE bool closest_on(SurfaceTag<SurfaceKind::splats>, const SceneView& s, const ModelRay& q,
                                  float t_max, ModelHit& out, RayCounters& c) {
    const BlendOptions blend{s.params.blend_window, s.params.deep_blending != 0};
    WalkStats ws;
    SplatSample h{};
    const bool hit = closest_hit_splats(q.mv.octree, q.mv.colors, q.o, q.d, q.inside, t_max, blend,
                                        s.params.max_steps, h, ws, s.params.leaf_culling);
    add_stats(c, ws);
    if (hit) out = ModelHit{h.t, h.normal, h.color, h.point};
    return hit;
}
PRT_HD PRT_INLINE bool occluded_on(SurfaceTag<SurfaceKind::splats>, const SceneView& s, const ModelRay& q,
                                   RayCounters& c) {
    WalkStats ws;
    const bool hit = any_hit_splats(q.mv.octree, q.o, q.d, q.inside, q.ray.t_max, s.params.max_steps, ws,
                                    s.params.leaf_culling);
    add_stats(c, ws);
    return hit;
}

/// A frame's level-of-detail cone (RenderParams::lod_spread, lod_eye) from its camera; the backends
/// call it for each frame.
PRT_HD PRT_INLINE void set_lod_cone(RenderParams& p, const PinholeCamera& cam, std::uint32_t height) {
    p.lod_spread = p.lod_pixels * pixel_angle(cam, height);
    p.lod_eye = cam.position;
}

// Bricked splats (issue 17, bricks.h): the same blending; colours from the splats, no source point.
// Level of detail: a ray's footprint t from its origin o is lod_spread * (|o - eye| + t) (bricks.h
// LodCone, in model units: render units times inv_scale). A camera ray starts at the eye (0 wide); a
// ray leaving a hit (shadow, reflected, refracted) starts with the pixel cone's width there, the ray
// cone of Amanatides 1984 carried through a bounce as Akenine-Moller et al. 2019 (Ray Tracing Gems,
// ch. 20) do with surfaces taken as planar: exact for the rays leaving a camera ray's hit, and for
// deeper bounces, |o - eye| being at most the path's length, never wider than that cone. So shadow
// and mirror rays stop no finer than the hits they leave (they asked for the full-resolution brick
// under every hit when they started 0 wide). The width comes from the ray's origin and the eye
// (RenderParams::lod_eye), so no ray carries it (a wider Ray cost the float kernel 7 %).
PRT_HD PRT_INLINE LodCone lod_cone(const SceneView& s, const ModelRay& q) {
    const float spread = s.params.lod_spread * q.mv.inv_scale;
    if (!(spread > 0.0f) || q.ray.from_model == k_no_model)
        return LodCone{0.0f, spread};  // camera rays: 0 wide
    return LodCone{spread * length(q.ray.origin - s.params.lod_eye), spread};
}
PRT_HD PRT_INLINE bool closest_on(BricksTag, const SceneView& s, const ModelRay& q, float t_max,
                                  ModelHit& out, RayCounters& c) {
    WalkStats ws;
    SplatSample h{};
    const bool hit = closest_hit_bricks(q.mv.bricks, q.o, q.d, q.inside, t_max,
                                        BlendOptions{s.params.blend_window, s.params.deep_blending != 0},
                                        s.params.max_steps, h, ws, s.params.leaf_culling, lod_cone(s, q));
    add_stats(c, ws);
    if (hit) out = ModelHit{h.t, h.normal, h.color, h.point};
    return hit;
}
PRT_HD PRT_INLINE bool occluded_on(BricksTag, const SceneView& s, const ModelRay& q, RayCounters& c) {
    WalkStats ws;
    const bool hit = any_hit_bricks(q.mv.bricks, q.o, q.d, q.inside, q.ray.t_max, s.params.max_steps, ws,
                                    s.params.leaf_culling, lod_cone(s, q));
    add_stats(c, ws);
    return hit;
}

/// The one surface dispatch: visit(SurfaceTag<kind>{}) for a model's surface kind (ISO: IsoTag), among the
/// kinds K carries; splats take whatever is not ISO, MLS or patches, as BricksTag when the model's
/// pool is bricked and K carries k_mask_bricks (a kernel is launched only for scenes whose surfaces
/// it carries: scene_mask()). False for a surface K does not carry.
template <std::uint32_t K, class Visit>
PRT_HD PRT_INLINE bool dispatch_surface(const ModelView& mv, Visit&& visit) {
    const SurfaceKind kind = mv.surface;
    if constexpr ((K & k_mask_iso) != 0)
        if (kind == SurfaceKind::iso) {
            if constexpr ((K & k_mask_plain_walk) != 0)
                return visit(IsoTag<false>{});
            else
                return visit(IsoTag<true>{});
        }
    if constexpr ((K & k_mask_mls) != 0)
        if (kind == SurfaceKind::mls) return visit(SurfaceTag<SurfaceKind::mls>{});
    if constexpr ((K & k_mask_patches) != 0)
        if (kind == SurfaceKind::patches) return visit(SurfaceTag<SurfaceKind::patches>{});
    if constexpr ((K & k_mask_bricks) != 0)
        if (kind == SurfaceKind::splats && mv.bricks.top_nodes != nullptr) return visit(BricksTag{});
    if constexpr ((K & k_mask_splats) != 0) return visit(SurfaceTag<SurfaceKind::splats>{});
    return false;
}

/// For each model of s in order: ray r in its frame (ModelRay) and its surface's tag go to
/// visit(tag, q), which returns true to stop. Returns whether a visit stopped the walk. Closest
/// hits and shadow rays (and through them every trace: trace_ray, path.h, the profiles) meet the
/// surfaces here only.
template <std::uint32_t K, class Visit>
PRT_HD PRT_INLINE bool for_each_surface(const SceneView& s, const Ray& r, Visit&& visit) {
    for (std::uint32_t m = 0; m < s.model_count; ++m) {
        const ModelView& mv = s.models[m];
        ModelRay q{mv, m, r, Vec3{}, Vec3{}, ray_inside(r)};
        to_model_frame(mv, r, q.o, q.d);
        if (dispatch_surface<K>(mv, [&](auto surface) { return visit(surface, q); })) return true;
    }
    return false;
}

/// The material a hit on model mv at source point `point` shades with: the point's material id
/// when the pool has them, else the model's, clamped to the scene's materials.
PRT_HD PRT_INLINE std::uint32_t hit_material(const SceneView& s, const ModelView& mv, std::uint32_t point) {
    std::uint32_t mat = mv.material;
    if (mv.material_ids != nullptr && point < mv.point_count) mat = mv.material_ids[point];
    if (mat >= s.material_count) mat = s.material_count > 0 ? s.material_count - 1 : 0;
    return mat;
}

/// Closest hit over all models, t in [0, r.t_max). Counters: RayCounters, add_stats().
template <std::uint32_t K = k_mask_all>
PRT_HD inline bool closest_hit_scene(const SceneView& s, const Ray& r, SurfaceHit& hit, RayCounters& c) {
    float best = r.t_max;
    bool found = false;
    ModelHit sample;
    std::uint32_t model = 0;
    for_each_surface<K>(s, r, [&](auto surface, const ModelRay& q) {
        ModelHit cand;
        if (closest_on(surface, s, q, best, cand, c) && (cand.t < best || !found)) {
            best = cand.t;
            sample = cand;
            model = q.model;
            found = true;
        }
        return false;
    });
    if (!found) return false;
    const ModelView& mv = s.models[model];
    const std::uint32_t mat = hit_material(s, mv, sample.point);
    hit.t = sample.t;
    hit.position = ray_at(r, sample.t);
    hit.normal = normalize(mv.rotation * sample.normal);
    hit.material = mat;
    hit.model = model;
    hit.prim = sample.prim;
    hit.u = sample.u;
    hit.v = sample.v;
    const bool colors = s.material_count > 0 && s.materials[mat].use_point_colors != 0;
    hit.base_color = colors ? srgb_to_linear(sample.color) : Vec3{1, 1, 1};
    return true;
}

/// Whether anything blocks the segment [0, r.t_max) of a shadow ray (thesis 5.2), any surface.
template <std::uint32_t K = k_mask_all>
PRT_HD inline bool occluded(const SceneView& s, const Ray& r, RayCounters& c) {
    return for_each_surface<K>(
        s, r, [&](auto surface, const ModelRay& q) { return occluded_on(surface, s, q, c); });
}

/// The scene hit of ray r from model `model`'s closest sample: position, world normal, material and
/// base color: closest_hit_scene's ending, for query_scene (closest_hit_scene keeps it written out,
/// as shade_hit does its pieces below: the other kernels' code stays as it was).
PRT_HD PRT_INLINE void scene_hit(const SceneView& s, const Ray& r, std::uint32_t model,
                                 const ModelHit& sample, SurfaceHit& hit) {
    const ModelView& mv = s.models[model];
    const std::uint32_t mat = hit_material(s, mv, sample.point);
    hit.t = sample.t;
    hit.position = ray_at(r, sample.t);
    hit.normal = normalize(mv.rotation * sample.normal);
    hit.material = mat;
    hit.model = model;
    hit.prim = sample.prim;
    hit.u = sample.u;
    hit.v = sample.v;
    const bool colors = s.material_count > 0 && s.materials[mat].use_point_colors != 0;
    hit.base_color = colors ? srgb_to_linear(sample.color) : Vec3{1, 1, 1};
}

/// One query, closest hit or shadow ray (`any`), from one call site: what trace_ray's shared loop
/// (ISO-only kernels with secondary rays, k_shared_walk) calls for both, so a warp's lanes tracing
/// shadow rays and lanes tracing closest hits run the same walk code together: ISO's walk takes
/// the choice as an argument (iso_walk). Only ISO has one (splat-shared-walk.patch in
/// preprocess/bench/results/h100-2026-12-06-issue19-iso-shared: slower for splats).
template <bool k_regions>
PRT_HD PRT_INLINE bool query_on(IsoTag<k_regions>, const SceneView& s, const ModelRay& q, bool any,
                                float t_max, ModelHit& out, RayCounters& c) {
    IsoHit h;
    IsoStats st;
    // A shadow ray stops at its first hit, so t_max is still its own (occluded_on's q.ray.t_max).
    const bool hit = iso_walk<k_regions>(q.mv.iso, q.o, q.d, t_max, q.inside, iso_params_for(s), any, h, st);
    add_stats(c, st);
    if (hit && !any)
        out = ModelHit{h.t, h.normal, (q.mv.iso.flags & pool::k_iso_colors) != 0 ? h.color : Vec3{1, 1, 1}};
    return hit;
}

/// closest_hit_scene (any = false: `hit` set on a hit) or occluded (any = true: `hit` untouched), the
/// same answers, through query_on.
template <std::uint32_t K>
PRT_HD inline bool query_scene(const SceneView& s, const Ray& r, bool any, SurfaceHit& hit, RayCounters& c) {
    float best = r.t_max;
    bool found = false;
    ModelHit sample;
    std::uint32_t model = 0;
    const bool blocked = for_each_surface<K>(s, r, [&](auto surface, const ModelRay& q) {
        ModelHit cand;
        if (!query_on(surface, s, q, any, best, cand, c)) return false;
        if (any) return true;
        if (cand.t < best || !found) {
            best = cand.t;
            sample = cand;
            model = q.model;
            found = true;
        }
        return false;
    });
    if (any) return blocked;
    if (!found) return false;
    scene_hit(s, r, model, sample, hit);
    return true;
}

/// A ray leaving the surface point h (shadow, reflected, refracted): starts exactly at the hit,
/// no offset (thesis 3.6), and remembers where it left (Ray::from_model).
PRT_HD PRT_INLINE Ray leave_surface(const SurfaceHit& h, Vec3 dir, float t_max, std::uint32_t flags) {
    Ray r{h.position, dir, t_max, flags};
    r.from_model = h.model;
    r.from_prim = h.prim;
    r.from_u = h.u;
    r.from_v = h.v;
    return r;
}

/// The core's answer to shadow rays (shade_hit's default).
template <std::uint32_t K>
struct SceneOcclusion {
    PRT_HD PRT_INLINE bool operator()(const SceneView& s, const Ray& r, RayCounters& c) const {
        return occluded<K>(s, r, c);
    }
};

/// The shading normal: the stored normal turned to face the incoming ray.
PRT_HD PRT_INLINE Vec3 facing_normal(const SurfaceHit& h, const Ray& r) {
    return dot(h.normal, r.dir) < 0.0f ? h.normal : -h.normal;
}

/// shade_hit's pieces for trace_ray_shared, which shades a hit's lights across passes (the same
/// arithmetic in the same order). shade_hit keeps them written out: called from it, they changed
/// the code ptxas made of every kernel (sm_90: the splat kernel's spill stores 700 -> 680 B), and
/// the one build measured so ran the splat kernels 1-2.5 % slower (with another change, not split;
/// preprocess/bench/results/h100-2026-12-06-issue19-iso-shared). Keep the two in step.
///
/// thesis 5.1 / 5.3 / 5.4.2: the hit's ambient term: the material's ambient times the base color, or
/// where the model has them the precomputed global illumination, looked up in the model's local
/// frame: the light map's indirect irradiance replaces the constant ambient term, the caustic
/// irradiance adds; both reflect with the diffuse albedo. `n`: the facing normal.
PRT_HD PRT_INLINE Vec3 ambient_term(const SceneView& s, const Material& m, const SurfaceHit& h, Vec3 n) {
    Vec3 sum = m.ambient * h.base_color;
    if (h.model < s.model_count) {
        const ModelView& mv = s.models[h.model];
        if (mv.light_map.tree.nodes != nullptr || mv.caustics.tree.nodes != nullptr) {
            const Vec3 lp = mul_transpose(mv.rotation, h.position - mv.offset) * mv.inv_scale;
            const Vec3 ln = mul_transpose(mv.rotation, n);
            Vec3 e;
            if (light_map_irradiance(mv.light_map, lp, ln, e)) sum = m.diffuse * h.base_color * e;
            sum += m.diffuse * h.base_color * caustic_radiance(mv.caustics, lp, ln);
        }
    }
    return sum;
}

/// The unit direction `l` and distance to a light from a hit, false when the light cannot light it
/// (at the hit, not finite, or behind the facing normal `n`).
PRT_HD PRT_INLINE bool light_direction(const PointLight& light, const SurfaceHit& h, Vec3 n, Vec3& l,
                                       float& dist) {
    const Vec3 to_light = light.position - h.position;
    dist = length(to_light);
    if (!(dist > 0.0f) || !is_finite(dist)) return false;
    l = to_light * (1.0f / dist);
    return dot(n, l) > 0.0f;
}

/// Whether a light's contribution waits on a shadow ray (thesis 5.2).
PRT_HD PRT_INLINE bool casts_shadow_ray(const SceneView& s, const PointLight& light) {
    return s.params.shadows != 0 && light.casts_shadows != 0;
}

/// thesis 5.1-5.2: local shading at a hit: ambient + sum over lights of Lambert + Phong, each
/// light tested with a shadow ray when shadows are on and the light casts them, all scaled by the
/// material's diffuse reflectance. Shadow rays keep the ray's front/back flag (thesis 3.6), so the
/// surface they leave never shadows itself.
/// `blocked(s, shadow_ray, c)` answers the shadow rays: by default the core's occluded<K>; a peer
/// renderer (prt-bench-embree) passes its own.
template <std::uint32_t K = k_mask_all, class Occlusion = SceneOcclusion<K>>
PRT_HD inline Vec3 shade_hit(const SceneView& s, const Ray& r, const SurfaceHit& h, RayCounters& c,
                             const Occlusion& blocked = Occlusion{}) {
    const Material& m = s.materials[h.material];
    if (!(m.diffuse_reflectance > 0.0f)) return Vec3{0, 0, 0};
    const Vec3 n = facing_normal(h, r);
    Vec3 sum = m.ambient * h.base_color;
    if (h.model < s.model_count) {
        // thesis 5.3 / 5.4.2: precomputed global illumination, looked up in the model's local frame:
        // the light map's indirect irradiance replaces the constant ambient term, the caustic
        // irradiance adds; both reflect with the diffuse albedo.
        const ModelView& mv = s.models[h.model];
        if (mv.light_map.tree.nodes != nullptr || mv.caustics.tree.nodes != nullptr) {
            const Vec3 lp = mul_transpose(mv.rotation, h.position - mv.offset) * mv.inv_scale;
            const Vec3 ln = mul_transpose(mv.rotation, n);
            Vec3 e;
            if (light_map_irradiance(mv.light_map, lp, ln, e)) sum = m.diffuse * h.base_color * e;
            sum += m.diffuse * h.base_color * caustic_radiance(mv.caustics, lp, ln);
        }
    }
    for (std::uint32_t i = 0; i < s.light_count; ++i) {
        const PointLight& light = s.lights[i];
        const Vec3 to_light = light.position - h.position;
        const float dist = length(to_light);
        if (!(dist > 0.0f) || !is_finite(dist)) continue;
        const Vec3 l = to_light * (1.0f / dist);
        if (!(dot(n, l) > 0.0f)) continue;
        if (s.params.shadows != 0 && light.casts_shadows != 0) {
            ++c.shadow;
            if (blocked(s, leave_surface(h, l, dist, r.flags), c)) continue;
        }
        sum += lambert_phong(m, h.base_color, n, l, r.dir, light.color);
    }
    return sum * m.diffuse_reflectance;
}

/// A ray waiting to be traced with the intensity it carries.
struct PendingRay {
    Ray ray;
    Vec3 weight;
    std::uint32_t depth;
};

/// thesis 3.3 + 7.2: the reflected and refracted rays leaving a hit, with their intensities
/// (weight x reflectivity, weight x transmissivity). Total internal reflection sends the
/// transmitted share along the reflection. Refraction flips the seamless flag (thesis 3.6);
/// reflection keeps it. Both start exactly at the hit point: no offset. Returns how many of
/// out[0..1] are set; rays below RenderParams::min_ray_weight or past the bounce limit are not.
PRT_HD inline std::uint32_t spawn_secondary(const SceneView& s, const PendingRay& in, const SurfaceHit& h,
                                            PendingRay out[2]) {
    const RenderParams& p = s.params;
    const std::uint32_t limit = p.max_bounces < k_max_bounces ? p.max_bounces : k_max_bounces;
    if (in.depth >= limit) return 0;
    const Material& m = s.materials[h.material];
    float kr = p.reflections != 0 ? fmaxf(m.reflectivity, 0.0f) : 0.0f;
    const float kt = p.refractions != 0 ? fmaxf(m.transmissivity, 0.0f) : 0.0f;
    const Vec3 n = facing_normal(h, in.ray);
    std::uint32_t count = 0;
    if (kt > 0.0f) {
        const bool inside = ray_inside(in.ray);
        const float ior = m.refractive_index > 0.0f ? m.refractive_index : 1.0f;
        const float eta = inside ? ior : 1.0f / ior;  // n1 / n2
        Vec3 dt;
        if (refract(in.ray.dir, n, eta, dt)) {
            const Vec3 w = in.weight * kt;
            if (max3(w) > p.min_ray_weight) {
                out[count++] =
                    PendingRay{leave_surface(h, dt, k_inf, in.ray.flags ^ k_ray_inside), w, in.depth + 1};
            }
        } else {
            kr += kt;  // total internal reflection
        }
    }
    if (kr > 0.0f) {
        const Vec3 w = in.weight * kr;
        if (max3(w) > p.min_ray_weight) {
            out[count++] = PendingRay{
                leave_surface(h, normalize(reflect(in.ray.dir, n)), k_inf, in.ray.flags), w, in.depth + 1};
        }
    }
    return count;
}

/// The core's closest hits and shading of trace_ray's rays (its default): any other Tracer offers
/// the same two calls (a peer renderer's queries, prt-bench-embree; the per-ray work records of
/// prt-bench --profile).
template <std::uint32_t K>
struct SceneTracer {
    PRT_HD PRT_INLINE bool closest(const SceneView& s, const PendingRay& p, SurfaceHit& h,
                                   RayCounters& c) const {
        return closest_hit_scene<K>(s, p.ray, h, c);
    }
    PRT_HD PRT_INLINE Vec3 shade(const SceneView& s, const PendingRay& p, const SurfaceHit& h,
                                 RayCounters& c) const {
        return shade_hit<K>(s, p.ray, h, c);
    }
};

/// Kernels whose rays share one walk loop (trace_ray_shared): ISO alone with secondary rays, or
/// without them for frames that trace shadow rays (k_mask_shadow_walk). Frames with neither trace
/// one closest hit per pixel and run trace_ray's plain path: the shared loop made those 6-10 %
/// slower and shadow frames 13-24 % faster (H100, 2026-12-06,
/// preprocess/bench/results/h100-2026-12-06-issue19-iso-shared, s4.txt).
template <std::uint32_t K>
inline constexpr bool k_shared_walk = (K & ~(k_mask_secondary | k_mask_shadow_walk |
                                             k_mask_plain_walk)) == k_mask_iso
                                      && (K & (k_mask_secondary | k_mask_shadow_walk)) != 0;

/// trace_ray with the default tracer for ISO-only kernels (k_shared_walk): the same rays, the
/// same sums in the same order (so the same image as trace_ray), but closest hits and shadow rays
/// leave from one call site (query_scene) in one loop, one query per pass: a hit's lights are
/// shaded across passes, each shadow ray a pass of its own. In trace_ray a warp whose lanes split
/// between a shadow ray (in shade_hit) and a closest hit runs the two walks one after the other;
/// here they are the same walk and run together (Aila and Laine 2009, 3: idle lanes are the cost).
/// Without k_mask_secondary no ray is spawned: the loop ends with the primary hit's last light.
template <std::uint32_t K>
PRT_HD inline Vec3 trace_ray_shared(const SceneView& s, const Ray& primary, RayCounters& c) {
    PendingRay stack[k_max_bounces + 1];
    std::uint32_t top = 0;
    PendingRay cur{primary, Vec3{1, 1, 1}, 0};
    Vec3 color{0, 0, 0};
    SurfaceHit h;
    Vec3 sum{0, 0, 0};        // the current hit's shading so far (shade_hit's sum)
    std::uint32_t light = 0;  // its light whose shadow ray the pass traces
    Ray q = primary;          // the pass's query: cur's closest hit, or light's shadow ray
    bool any = false;
    // Bounded: each pass answers one query; a hit asks at most light_count shadow rays and spawns
    // at most two rays, only below the bounce limit (trace_ray's bound).
    for (;;) {
        const bool hit = query_scene<K>(s, q, any, h, c);
        bool shading = any;   // cur's hit has lights left to shade
        bool shaded = false;  // cur's hit is shaded: spawn its rays
        if (!any) {
            if (!hit) {
                color += cur.weight * background(s.environment, cur.ray.dir);
            } else {
                const Material& m = s.materials[h.material];
                if (!(m.diffuse_reflectance > 0.0f)) {
                    color += cur.weight * Vec3{0, 0, 0};
                    shaded = true;
                } else {
                    sum = ambient_term(s, m, h, facing_normal(h, cur.ray));
                    light = 0;
                    shading = true;
                }
            }
        } else {
            if (!hit) {
                Vec3 l;
                float dist;
                const Vec3 n = facing_normal(h, cur.ray);
                light_direction(s.lights[light], h, n, l, dist);
                sum += lambert_phong(s.materials[h.material], h.base_color, n, l, cur.ray.dir,
                                     s.lights[light].color);
            }
            ++light;
        }
        if (shading) {
            // The lights left of this hit: shade those without a shadow ray, stop at the next one
            // with a shadow ray (the next pass traces it).
            const Material& m = s.materials[h.material];
            const Vec3 n = facing_normal(h, cur.ray);
            any = false;
            for (; light < s.light_count; ++light) {
                const PointLight& pl = s.lights[light];
                Vec3 l;
                float dist;
                if (!light_direction(pl, h, n, l, dist)) continue;
                if (casts_shadow_ray(s, pl)) {
                    ++c.shadow;
                    q = leave_surface(h, l, dist, cur.ray.flags);
                    any = true;
                    break;
                }
                sum += lambert_phong(m, h.base_color, n, l, cur.ray.dir, pl.color);
            }
            if (any) continue;
            color += cur.weight * (sum * m.diffuse_reflectance);
            shaded = true;
        }
        any = false;
        if ((K & k_mask_secondary) != 0 && shaded) {
            PendingRay next[2];
            const std::uint32_t n = spawn_secondary(s, cur, h, next);
            c.secondary += n;
            if (n == 2) {
                if (top < k_max_bounces + 1)
                    stack[top++] = next[1];
                else
                    ++c.dropped;
            }
            if (n > 0) {
                cur = next[0];
                q = cur.ray;
                continue;
            }
        }
        if (top == 0) break;
        cur = stack[--top];
        q = cur.ray;
    }
    return color;
}

/// Traces a primary ray and everything it spawns, iteratively: one branch continues in the
/// loop, the other waits on a fixed stack (depth-first, so at most k_max_bounces + 1 entries).
/// Misses see the background. Returns linear radiance. `tracer` answers the closest hits and
/// shades them (SceneTracer: the core's own).
template <std::uint32_t K = k_mask_all, class Tracer = SceneTracer<K>>
PRT_HD inline Vec3 trace_ray(const SceneView& s, const Ray& primary, RayCounters& c,
                             const Tracer& tracer = Tracer{}) {
    ++c.primary;
    if constexpr (k_shared_walk<K> && std::is_same_v<Tracer, SceneTracer<K>>) {
        return trace_ray_shared<K>(s, primary, c);
    } else if constexpr ((K & k_mask_secondary) == 0) {
        // A frame that spawns no secondary ray (spawns_secondary): the loop below would end after
        // its first ray; without the stack of pending rays the kernel keeps fewer registers and a
        // fifth of the local memory (splat kernel, sm_90: 328 B stack and 440 B of spills against
        // 1648 B and 708 B).
        const PendingRay only{primary, Vec3{1, 1, 1}, 0};
        SurfaceHit h;
        if (!tracer.closest(s, only, h, c)) return background(s.environment, primary.dir);
        return tracer.shade(s, only, h, c);
    } else {
        PendingRay stack[k_max_bounces + 1];
        std::uint32_t top = 0;
        PendingRay cur{primary, Vec3{1, 1, 1}, 0};
        Vec3 color{0, 0, 0};
        // Bounded: each iteration traces one ray; a ray spawns at most two, only below the bounce
        // limit, so at most 2^(k_max_bounces+1) rays; the weight cut-off keeps real counts small.
        for (;;) {
            SurfaceHit h;
            if (!tracer.closest(s, cur, h, c)) {
                color += cur.weight * background(s.environment, cur.ray.dir);
            } else {
                color += cur.weight * tracer.shade(s, cur, h, c);
                PendingRay next[2];
                const std::uint32_t n = spawn_secondary(s, cur, h, next);
                c.secondary += n;
                if (n == 2) {
                    if (top < k_max_bounces + 1)
                        stack[top++] = next[1];
                    else
                        ++c.dropped;
                }
                if (n > 0) {
                    cur = next[0];
                    continue;
                }
            }
            if (top == 0) break;
            cur = stack[--top];
        }
        return color;
    }
}

/// A pixel's radiance as it leaves the renderer: non-finite values become black and are counted.
PRT_HD PRT_INLINE Vec3 sanitize(Vec3 color, RayCounters& c) {
    if (is_finite(color)) return color;
    ++c.sanitized;
    return Vec3{0, 0, 0};
}

}  // namespace prt::core

#include "prt/core/path.h"

namespace prt::core {

/// One pixel: with one sample the primary ray through its centre, ray traced (thesis 2-3, 5);
/// otherwise RenderParams::spp stratified samples, path traced when RenderParams::path_tracing
/// (seed 002, 7; path.h). Never NaN (replaced and counted).
/// K (KernelMask) limits the code to the surfaces and modes a kernel needs (scene_mask()).
template <std::uint32_t K = k_mask_all>
PRT_HD inline Vec3 render_pixel(const SceneView& s, const PinholeCamera& cam, std::uint32_t x,
                                std::uint32_t y, std::uint32_t width, std::uint32_t height, RayCounters& c) {
    if constexpr ((K & k_mask_sampling) != 0) {
        if (s.params.spp > 1 || s.params.path_tracing != 0)
            return sample_pixel(s, cam, x, y, width, height, c);
    }
    return sanitize(trace_ray<K>(s, primary_ray(cam, x, y, width, height), c), c);
}

}  // namespace prt::core
