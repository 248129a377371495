// PointRT core, for prt-lightmap: the indirect irradiance at a surface sample (thesis 5.3: "the output of a
// precomputation phase where a path tracer ... is used to compute the indirect illumination"),
// host + device (PRT_HD) over the renderer's core (prt/core/render.h).
//
// Units follow the renderer: a point light of color I gives a surface E = I cos(theta) (no
// falloff), and a diffuse surface sends albedo x E. The indirect irradiance at a sample is
// E_ind = integral of L cos / pi over the hemisphere = the mean of L over cosine-distributed
// directions, so each sample averages `rays` paths of up to `bounces` vertices: at every vertex the
// path gains the direct light there (Lambert, shadow rays as the renderer casts them, times the
// diffuse share) and then continues by one event drawn in proportion to the material's diffuse
// share (cosine-distributed bounce, x albedo), reflectivity (mirror) and transmissivity
// (refraction), with weight x (their sum). Misses see the background. Caustic paths (L S+ D) need
// the light to be hit and belong to prt-photons; these are the L D (S|D)* D paths.
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/photon.h"
#include "prt/core/render.h"  // and path.h, which it includes at its end
#include "prt/core/scene_view.h"
#include "prt/core/shading.h"

namespace prt::core {

struct LightMapTraceParams {
    std::uint32_t rays = 64;    ///< paths per sample
    std::uint32_t bounces = 3;  ///< vertices per path
    std::uint64_t seed = 1;
};

/// thesis 5.3: the radiance path number `k` of sample `sample` brings to a sample on the side of
/// unit normal `n`, leaving in a cosine-distributed direction; `first_ray(dir)` makes its first ray.
/// (sample, k) seed the random numbers, so every backend draws the same path (the GPU runs a
/// sample's paths in parallel, the CPU one after the other).
template <std::uint32_t K = k_mask_all, class FirstRay>
PRT_HD inline Vec3 light_map_path(const SceneView& s, const LightMapTraceParams& tp, Vec3 n,
                                  std::uint64_t sample, std::uint32_t k, RayCounters& c,
                                  FirstRay&& first_ray) {
    Vec3 sum{0, 0, 0};
    {
        std::uint64_t h = hash64(tp.seed ^ hash64(sample * 0x9e3779b97f4a7c15ull + k));
        const float u1 = unit_float(h);
        h = hash64(h);
        Ray ray = first_ray(cosine_direction(n, u1, unit_float(h)));
        Vec3 weight{1, 1, 1};
        // Bounded: at most `bounces` closest-hit queries per path.
        for (std::uint32_t b = 0; b < tp.bounces; ++b) {
            SurfaceHit hit;
            ++c.secondary;
            if (!closest_hit_scene<K>(s, ray, hit, c)) {
                sum += weight * background(s.environment, ray.dir);
                break;
            }
            const Material& m = s.materials[hit.material];
            const float d = fmaxf(m.diffuse_reflectance, 0.0f), kr = fmaxf(m.reflectivity, 0.0f),
                        kt = fmaxf(m.transmissivity, 0.0f);
            const Vec3 nf = facing_normal(hit, ray);
            const Vec3 albedo = m.diffuse * hit.base_color;
            if (d > 0.0f) {
                // The renderer's direct light (path.h: point lights, area lights sampled by area).
                PathRng rng{static_cast<std::uint32_t>(h >> 32)};
                sum += weight * direct_light<K>(s, ray, hit, nf, albedo, rng, c) * d;
            }
            const float total = d + kr + kt;
            if (!(total > 0.0f) || b + 1 == tp.bounces) break;
            h = hash64(h);
            const float u = unit_float(h) * total;
            weight = weight * total;
            if (u < d) {
                h = hash64(h);
                const float a1 = unit_float(h);
                h = hash64(h);
                weight = weight * albedo;
                ray = leave_surface(hit, cosine_direction(nf, a1, unit_float(h)), k_inf, ray.flags);
                continue;
            }
            bool refracted = false;
            if (u >= d + kr) {
                const float ior = m.refractive_index > 0.0f ? m.refractive_index : 1.0f;
                Vec3 t;
                if (refract(ray.dir, nf, ray_inside(ray) ? ior : 1.0f / ior, t)) {
                    ray = leave_surface(hit, t, k_inf, ray.flags ^ k_ray_inside);
                    refracted = true;
                }
            }
            if (!refracted) ray = leave_surface(hit, normalize(reflect(ray.dir, nf)), k_inf, ray.flags);
        }
    }
    return sum;
}

/// thesis 5.3: the mean radiance of `tp.rays` paths (light_map_path) leaving a sample.
template <class FirstRay>
PRT_HD inline Vec3 indirect_irradiance_paths(const SceneView& s, const LightMapTraceParams& tp, Vec3 n,
                                             std::uint64_t sample, RayCounters& c, FirstRay&& first_ray) {
    Vec3 sum{0, 0, 0};
    for (std::uint32_t k = 0; k < tp.rays; ++k) sum += light_map_path(s, tp, n, sample, k, c, first_ray);
    return tp.rays > 0 ? sum * (1.0f / static_cast<float>(tp.rays)) : sum;
}

/// thesis 5.3: indirect irradiance at render-frame point `p` on the side of unit normal `n` (a splat
/// model's sample: its point lies on its splat, and paths start there).
PRT_HD inline Vec3 indirect_irradiance(const SceneView& s, const LightMapTraceParams& tp, Vec3 p, Vec3 n,
                                       std::uint64_t sample, RayCounters& c) {
    return indirect_irradiance_paths(s, tp, n, sample, c, [&](Vec3 d) { return Ray{p, d, k_inf, 0u}; });
}

/// Issue 20: a light-map sample of a model traced as ISO, MLS or patches starts on the surface the
/// renderer traces, not at the scan point it was drawn from (an ISO or MLS surface passes near the
/// points, not through them: paths leaving a point just under it would see the surface's inside).
/// The probe ray from p + reach n toward -n, up to 2 reach: its closest hit, when it lies on model
/// `model`, is the sample's surface point. False when the probe misses or meets another model first.
template <std::uint32_t K = k_mask_all>
PRT_HD inline bool settle_sample(const SceneView& s, std::uint32_t model, Vec3 p, Vec3 n, float reach,
                                 SurfaceHit& hit, Vec3& side, RayCounters& c) {
    const Ray probe{p + n * reach, -n, 2.0f * reach, 0u};
    ++c.secondary;
    if (!closest_hit_scene<K>(s, probe, hit, c) || hit.model != model) return false;
    side = facing_normal(hit, probe);  // the side the probe came from: n's
    return true;
}

/// One light-map sample as the tracers take it (render frame): where, which side, its model and how
/// far it is probed for the traced surface (0: not probed, splats).
struct LightMapSampleIn {
    Vec3 position, normal;
    std::uint32_t model = 0;
    float settle_reach = 0.0f;
};

/// What tracing one sample gives: its indirect irradiance and, when probed, the surface point and
/// side it settled on (render frame); settled 0 when the probe found no surface of its model.
struct LightMapSampleOut {
    Vec3 irradiance{0, 0, 0}, position{0, 0, 0}, side{0, 0, 0};
    std::uint32_t settled = 1;
};

/// Issue 20: where a sample's paths start: settled onto the traced surface when it has a settle
/// reach (settle_sample; false when the probe found no surface of its model), else at its point.
template <std::uint32_t K = k_mask_all>
PRT_HD inline bool light_map_start(const SceneView& s, const LightMapSampleIn& in, SurfaceHit& hit,
                                   Vec3& side, RayCounters& c) {
    side = in.normal;
    if (!(in.settle_reach > 0.0f)) return true;
    return settle_sample<K>(s, in.model, in.position, in.normal, in.settle_reach, hit, side, c);
}

/// Path number `k` of light-map sample number `index` from its start (light_map_start).
template <std::uint32_t K = k_mask_all>
PRT_HD inline Vec3 light_map_sample_path(const SceneView& s, const LightMapTraceParams& tp,
                                         const LightMapSampleIn& in, const SurfaceHit& hit, Vec3 side,
                                         std::uint64_t index, std::uint32_t k, RayCounters& c) {
    if (in.settle_reach > 0.0f)
        return light_map_path<K>(s, tp, side, index, k, c,
                                 [&](Vec3 d) { return leave_surface(hit, d, k_inf, 0u); });
    return light_map_path<K>(s, tp, side, index, k, c, [&](Vec3 d) {
        return Ray{in.position, d, k_inf, 0u};
    });
}

/// thesis 5.3 (+ issue 20's settling): traces light-map sample number `index`: its start, then its
/// paths one after the other (the CPU path; the GPU kernel, runtime/cuda/src/lightmap.cu, runs the
/// same light_map_start and light_map_sample_path with a sample's paths in parallel).
PRT_HD inline LightMapSampleOut trace_light_map_sample(const SceneView& s, const LightMapTraceParams& tp,
                                                       const LightMapSampleIn& in, std::uint64_t index,
                                                       RayCounters& c) {
    LightMapSampleOut out;
    SurfaceHit hit;
    out.position = in.position;
    if (!light_map_start(s, in, hit, out.side, c)) {
        out.settled = 0;
        return out;
    }
    if (in.settle_reach > 0.0f) out.position = hit.position;
    for (std::uint32_t k = 0; k < tp.rays; ++k)
        out.irradiance += light_map_sample_path(s, tp, in, hit, out.side, index, k, c);
    if (tp.rays > 0) out.irradiance = out.irradiance * (1.0f / static_cast<float>(tp.rays));
    return out;
}

}  // namespace prt::core
