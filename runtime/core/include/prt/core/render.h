// PointRT core: one ray tracer for every backend. Closest hits over all models, local shading
// with shadow rays, reflection and refraction with per-ray intensity and a bounce limit, all
// iterative (thesis 2: no recursion on the GPU) with a fixed-size ray stack.
//
// Backends call render_pixel() (one thread per pixel: the CPU backend and the CUDA megakernel), or
// the three stages closest_hit_scene() / shade_hit() / spawn_secondary() separately (the CUDA
// wavefront kernels of thesis 2.4).
#pragma once

#include <cstdint>

#include "prt/core/camera.h"
#include "prt/core/math.h"
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
};

PRT_HD PRT_INLINE void add_walk_stats(RayCounters& c, const WalkStats& w) {
    c.leaves += w.leaves;
    c.splat_tests += w.splat_tests;
    c.truncated += w.truncated;
    c.culled += w.culled;
}

/// A shaded surface point in the render frame.
struct SurfaceHit {
    float t;
    Vec3 position;
    Vec3 normal;      ///< unit, outward (as stored); the ray's flag says which face was hit
    Vec3 base_color;  ///< linear; (1,1,1) when the material ignores point colors
    std::uint32_t material;
};

/// The ray in a model's local frame (t is unchanged: d is scaled, not normalized).
PRT_HD PRT_INLINE void to_model_frame(const ModelView& m, const Ray& r, Vec3& o, Vec3& d) {
    o = mul_transpose(m.rotation, r.origin - m.offset) * m.inv_scale;
    d = mul_transpose(m.rotation, r.dir) * m.inv_scale;
}

/// Closest hit over all models (thesis 2.2 traversal + 3.3 blending), t in [0, r.t_max).
PRT_HD inline bool closest_hit_scene(const SceneView& s, const Ray& r, SurfaceHit& hit, RayCounters& c) {
    const BlendOptions blend{s.params.blend_window, s.params.deep_blending != 0};
    float best = r.t_max;
    bool found = false;
    SplatSample sample{};
    std::uint32_t model = 0;
    for (std::uint32_t m = 0; m < s.model_count; ++m) {
        const ModelView& mv = s.models[m];
        Vec3 o, d;
        to_model_frame(mv, r, o, d);
        WalkStats ws;
        SplatSample cand{};
        if (closest_hit_splats(mv.octree, mv.colors, o, d, ray_inside(r), best, blend, s.params.max_steps,
                               cand, ws, s.params.leaf_culling)) {
            if (cand.t < best || !found) {
                best = cand.t;
                sample = cand;
                model = m;
                found = true;
            }
        }
        add_walk_stats(c, ws);
    }
    if (!found) return false;
    const ModelView& mv = s.models[model];
    std::uint32_t mat = mv.material;
    if (mv.material_ids != nullptr && sample.point < mv.point_count) mat = mv.material_ids[sample.point];
    if (mat >= s.material_count) mat = s.material_count > 0 ? s.material_count - 1 : 0;
    hit.t = sample.t;
    hit.position = ray_at(r, sample.t);
    hit.normal = normalize(mv.rotation * sample.normal);
    hit.material = mat;
    const bool colors =
        mv.colors != nullptr && s.material_count > 0 && s.materials[mat].use_point_colors != 0;
    hit.base_color = colors ? srgb_to_linear(sample.color) : Vec3{1, 1, 1};
    return true;
}

/// Whether anything blocks the segment [0, r.t_max) of a shadow ray (thesis 5.2).
PRT_HD inline bool occluded(const SceneView& s, const Ray& r, RayCounters& c) {
    for (std::uint32_t m = 0; m < s.model_count; ++m) {
        const ModelView& mv = s.models[m];
        Vec3 o, d;
        to_model_frame(mv, r, o, d);
        WalkStats ws;
        const bool hit = any_hit_splats(mv.octree, o, d, ray_inside(r), r.t_max, s.params.max_steps, ws,
                                        s.params.leaf_culling);
        add_walk_stats(c, ws);
        if (hit) return true;
    }
    return false;
}

/// The shading normal: the stored normal turned to face the incoming ray.
PRT_HD PRT_INLINE Vec3 facing_normal(const SurfaceHit& h, const Ray& r) {
    return dot(h.normal, r.dir) < 0.0f ? h.normal : -h.normal;
}

/// thesis 5.1-5.2: local shading at a hit: ambient + sum over lights of Lambert + Phong, each
/// light tested with a shadow ray when shadows are on and the light casts them, all scaled by the
/// material's diffuse reflectance. Shadow rays keep the ray's front/back flag (thesis 3.6), so the
/// surface they leave never shadows itself.
PRT_HD inline Vec3 shade_hit(const SceneView& s, const Ray& r, const SurfaceHit& h, RayCounters& c) {
    const Material& m = s.materials[h.material];
    if (!(m.diffuse_reflectance > 0.0f)) return Vec3{0, 0, 0};
    const Vec3 n = facing_normal(h, r);
    Vec3 sum = m.ambient * h.base_color;
    for (std::uint32_t i = 0; i < s.light_count; ++i) {
        const PointLight& light = s.lights[i];
        const Vec3 to_light = light.position - h.position;
        const float dist = length(to_light);
        if (!(dist > 0.0f) || !is_finite(dist)) continue;
        const Vec3 l = to_light * (1.0f / dist);
        if (!(dot(n, l) > 0.0f)) continue;
        if (s.params.shadows != 0 && light.casts_shadows != 0) {
            ++c.shadow;
            if (occluded(s, Ray{h.position, l, dist, r.flags}, c)) continue;
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
                    PendingRay{Ray{h.position, dt, k_inf, in.ray.flags ^ k_ray_inside}, w, in.depth + 1};
            }
        } else {
            kr += kt;  // total internal reflection
        }
    }
    if (kr > 0.0f) {
        const Vec3 w = in.weight * kr;
        if (max3(w) > p.min_ray_weight) {
            out[count++] = PendingRay{Ray{h.position, normalize(reflect(in.ray.dir, n)), k_inf, in.ray.flags},
                                      w, in.depth + 1};
        }
    }
    return count;
}

/// Traces a primary ray and everything it spawns, iteratively: one branch continues in the
/// loop, the other waits on a fixed stack (depth-first, so at most k_max_bounces + 1 entries).
/// Misses see the background. Returns linear radiance.
PRT_HD inline Vec3 trace_ray(const SceneView& s, const Ray& primary, RayCounters& c) {
    PendingRay stack[k_max_bounces + 1];
    std::uint32_t top = 0;
    PendingRay cur{primary, Vec3{1, 1, 1}, 0};
    Vec3 color{0, 0, 0};
    ++c.primary;
    // Bounded: each iteration traces one ray; a ray spawns at most two, only below the bounce
    // limit, so at most 2^(k_max_bounces+1) rays; the weight cut-off keeps real counts small.
    for (;;) {
        SurfaceHit h;
        if (!closest_hit_scene(s, cur.ray, h, c)) {
            color += cur.weight * background(s.environment, cur.ray.dir);
        } else {
            color += cur.weight * shade_hit(s, cur.ray, h, c);
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

/// One pixel: the primary ray through its centre, traced; never NaN (replaced and counted).
PRT_HD inline Vec3 render_pixel(const SceneView& s, const PinholeCamera& cam, std::uint32_t x,
                                std::uint32_t y, std::uint32_t width, std::uint32_t height, RayCounters& c) {
    const Ray r = primary_ray(cam, x, y, width, height);
    Vec3 color = trace_ray(s, r, c);
    if (!is_finite(color)) {
        color = Vec3{0, 0, 0};
        ++c.sanitized;
    }
    return color;
}

}  // namespace prt::core
