// PointRT core: Monte Carlo path tracing (seed 002, section 7) over every surface (splats, ISO,
// MLS, patches), on the CPU and in the CUDA megakernel through the same function.
//
// seed 002, 7: each pixel gets s samples, stratified (the paper splits the pixel into 4 quadrants;
// here into a ceil(sqrt(s)) x ceil(sqrt(s)) grid, one jittered sample per cell, which is the
// same for s = 4); a path continues from a diffuse surface in a random direction and from a
// specular patch along the mirror direction, and ends when it (a) hits a light, (b) leaves the
// scene, or (c) reaches the maximum depth (10), where direct light is gathered by a shadow ray to
// a random point of the light.
//
// Generalized to the scene's materials (thesis 5.1) and lights (5.2), keeping the Whitted
// renderer's light convention (render.h shade_hit: a light delivers color x intensity x cos, no
// distance falloff, so a path traced image converges to the ray traced one plus indirect light):
//  * at every hit one event is chosen with the material's fractions: perfect reflection
//    (reflectivity), refraction (transmissivity; total internal reflection reflects), diffuse
//    (diffuse_reflectance), or absorption (the rest) - Russian roulette on the material's own
//    split, so each path carries weight 1 times colors and stays unbiased;
//  * at a diffuse event: direct light by next-event estimation from every point light and one
//    uniformly chosen point of each area light (SCENE.md: "the path tracer samples it uniformly
//    by area"), shadow rays included, then a cosine-distributed bounce (weight: the albedo,
//    diffuse x point color) - at every depth, not only the last (lower variance, same limit);
//  * lights are seen by camera rays and after perfect reflections/refractions only: area lights
//    as emitting parallelograms of radiance color x intensity; light reaching a diffuse surface
//    through mirrors and glass (caustics) is left to the photon map (thesis 5.4), so nothing is
//    counted twice;
//  * the environment (color or latitude-longitude image) lights every path that leaves the scene.
// Everything is iterative and bounded by RenderParams::max_path_depth; no recursion, no stack.
// Included by render.h (after trace_ray and the hit functions, which it uses).
#pragma once

#include <cstdint>

#include "prt/core/camera.h"
#include "prt/core/math.h"
#include "prt/core/scene_view.h"
#include "prt/core/shading.h"

namespace prt::core {

/// A small, stateless-seeded generator (PCG-style hash then LCG steps): the same sequence on the
/// CPU and the GPU for a pixel, sample and frame.
struct PathRng {
    std::uint32_t state;
};

PRT_HD PRT_INLINE std::uint32_t pcg_hash(std::uint32_t v) {
    const std::uint32_t s = v * 747796405u + 2891336453u;
    const std::uint32_t w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (w >> 22u) ^ w;
}

PRT_HD PRT_INLINE PathRng make_rng(std::uint32_t pixel, std::uint32_t sample, std::uint32_t frame) {
    return PathRng{pcg_hash(pixel ^ pcg_hash(sample ^ pcg_hash(frame + 0x9e3779b9u)))};
}

/// Uniform in [0, 1).
PRT_HD PRT_INLINE float next_float(PathRng& r) {
    r.state = r.state * 747796405u + 2891336453u;
    const std::uint32_t v = pcg_hash(r.state);
    return static_cast<float>(v >> 8) * (1.0f / 16777216.0f);
}

/// An orthonormal basis around unit n (Duff et al. 2017 branchless construction).
PRT_HD PRT_INLINE void basis(Vec3 n, Vec3& t, Vec3& b) {
    const float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = Vec3{1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x};
    b = Vec3{c, sign + n.y * n.y * a, -n.y};
}

/// A cosine-distributed direction about unit n (pdf cos / pi).
PRT_HD PRT_INLINE Vec3 cosine_direction(Vec3 n, float u1, float u2) {
    const float r = sqrtf(u1);
    const float phi = 2.0f * k_pi * u2;
    const float x = r * cosf(phi), y = r * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
    Vec3 t, b;
    basis(n, t, b);
    return normalize(t * x + b * y + n * z);
}

/// The nearest area light the ray meets before t_max (t > 0), or -1; `t_hit` gets its distance.
PRT_HD inline int hit_area_light(const SceneView& s, const Ray& r, float t_max, float& t_hit) {
    int found = -1;
    t_hit = t_max;
    for (std::uint32_t i = 0; i < s.area_light_count; ++i) {
        const AreaLight& a = s.area_lights[i];
        const Vec3 n = cross(a.edge_u, a.edge_v);
        const float denom = dot(n, r.dir);
        if (denom == 0.0f) continue;
        const float t = dot(n, a.corner - r.origin) / denom;
        if (!(t > 0.0f) || !(t < t_hit)) continue;
        const Vec3 q = r.origin + r.dir * t - a.corner;
        // Parallelogram coordinates of q (edges need not be orthogonal).
        const float uu = dot(a.edge_u, a.edge_u), uv = dot(a.edge_u, a.edge_v), vv = dot(a.edge_v, a.edge_v);
        const float qu = dot(q, a.edge_u), qv = dot(q, a.edge_v);
        const float det = uu * vv - uv * uv;
        if (!(det > 0.0f)) continue;
        const float u = (qu * vv - qv * uv) / det, v = (qv * uu - qu * uv) / det;
        if (u < 0.0f || u > 1.0f || v < 0.0f || v > 1.0f) continue;
        t_hit = t;
        found = static_cast<int>(i);
    }
    return found;
}

/// Direct light at a diffuse hit (thesis 5.2 light convention; shadow rays keep the ray's flag).
/// K (KernelMask): the surfaces its shadow rays may meet.
template <std::uint32_t K = k_mask_all>
PRT_HD inline Vec3 direct_light(const SceneView& s, const Ray& r, const SurfaceHit& h, Vec3 n, Vec3 albedo,
                                PathRng& rng, RayCounters& c) {
    Vec3 sum{0, 0, 0};
    auto one = [&](Vec3 position, Vec3 color, std::uint32_t shadows) {
        const Vec3 to = position - h.position;
        const float dist = length(to);
        if (!(dist > 0.0f) || !is_finite(dist)) return;
        const Vec3 l = to * (1.0f / dist);
        const float ndl = dot(n, l);
        if (!(ndl > 0.0f)) return;
        if (s.params.shadows != 0 && shadows != 0) {
            ++c.shadow;
            if (occluded<K>(s, leave_surface(h, l, dist, r.flags), c)) return;
        }
        sum += color * albedo * ndl;
    };
    for (std::uint32_t i = 0; i < s.point_light_count; ++i)
        one(s.lights[i].position, s.lights[i].color, s.lights[i].casts_shadows);
    for (std::uint32_t i = 0; i < s.area_light_count; ++i) {
        const AreaLight& a = s.area_lights[i];
        const float u = next_float(rng), v = next_float(rng);
        one(a.corner + a.edge_u * u + a.edge_v * v, a.color, a.casts_shadows);
    }
    return sum;
}

/// One path from a camera ray: linear radiance (seed 002, 7; see the header comment).
PRT_HD inline Vec3 trace_path(const SceneView& s, Ray ray, PathRng& rng, RayCounters& c) {
    const RenderParams& p = s.params;
    Vec3 color{0, 0, 0}, weight{1, 1, 1};
    bool specular_chain = true;  // every event so far was a perfect reflection/refraction
    ++c.primary;
    for (std::uint32_t depth = 0;; ++depth) {
        SurfaceHit h;
        const bool hit = closest_hit_scene(s, ray, h, c);
        if (specular_chain) {
            float t_light;
            const int light = hit_area_light(s, ray, hit ? h.t : ray.t_max, t_light);
            if (light >= 0) {
                color += weight * s.area_lights[light].color;
                break;  // (a) the path hit a light
            }
        }
        if (!hit) {
            color += weight * background(s.environment, ray.dir);  // (b) it left the scene
            break;
        }
        const Material& m = s.materials[h.material];
        const Vec3 n = facing_normal(h, ray);
        const float kr = p.reflections != 0 ? fmaxf(m.reflectivity, 0.0f) : 0.0f;
        const float kt = p.refractions != 0 ? fmaxf(m.transmissivity, 0.0f) : 0.0f;
        const float kd = fmaxf(m.diffuse_reflectance, 0.0f);
        const Vec3 albedo = m.diffuse * h.base_color;
        if (depth + 1 >= p.max_path_depth) {
            // (c) the maximum depth: direct light only.
            if (kd > 0.0f) color += weight * direct_light(s, ray, h, n, albedo, rng, c) * kd;
            break;
        }
        const float xi = next_float(rng);
        if (xi < kr) {
            ray = leave_surface(h, normalize(reflect(ray.dir, n)), k_inf, ray.flags);
        } else if (xi < kr + kt) {
            const bool inside = ray_inside(ray);
            const float ior = m.refractive_index > 0.0f ? m.refractive_index : 1.0f;
            Vec3 dt;
            if (refract(ray.dir, n, inside ? ior : 1.0f / ior, dt))
                ray = leave_surface(h, dt, k_inf, ray.flags ^ k_ray_inside);
            else
                ray = leave_surface(h, normalize(reflect(ray.dir, n)), k_inf, ray.flags);  // TIR
        } else if (xi < kr + kt + kd) {
            color += weight * direct_light(s, ray, h, n, albedo, rng, c);
            weight = weight * albedo;
            if (!(max3(weight) > p.min_ray_weight)) break;
            const float u1 = next_float(rng), u2 = next_float(rng);
            ray = leave_surface(h, cosine_direction(n, u1, u2), k_inf, ray.flags);
            specular_chain = false;
        } else {
            break;  // absorbed
        }
        ++c.secondary;
    }
    return color;
}

/// The radiance of pixel (x, y) from `spp` stratified samples of frame `frame` (seed 002, 7:
/// jittered samples in a grid of cells over the pixel), path traced or ray traced (antialiasing).
PRT_HD inline Vec3 sample_pixel(const SceneView& s, const PinholeCamera& cam, std::uint32_t x,
                                std::uint32_t y, std::uint32_t width, std::uint32_t height, RayCounters& c) {
    const RenderParams& p = s.params;
    const std::uint32_t spp = p.spp > 0 ? p.spp : 1;
    std::uint32_t grid = 1;
    while (grid * grid < spp) ++grid;
    PathRng rng = make_rng(y * width + x, 0, p.frame);
    Vec3 sum{0, 0, 0};
    for (std::uint32_t i = 0; i < spp; ++i) {
        // Cell i of the grid (cells beyond spp unused), jittered; frame f shifts the cell order.
        const std::uint32_t cell = (i + p.frame * spp) % (grid * grid);
        const float sx = (static_cast<float>(cell % grid) + next_float(rng)) / static_cast<float>(grid);
        const float sy = (static_cast<float>(cell / grid) + next_float(rng)) / static_cast<float>(grid);
        const Ray r = primary_ray(cam, x, y, width, height, sx, sy);
        const Vec3 v = p.path_tracing != 0 ? trace_path(s, r, rng, c) : trace_ray(s, r, c);
        if (is_finite(v))
            sum += v;
        else
            ++c.sanitized;
    }
    return sum * (1.0f / static_cast<float>(spp));
}

}  // namespace prt::core
