// PointRT core: photon shooting (thesis 5.4.1), host + device (PRT_HD), for prt-photons. Its CPU
// path (preprocess/photons/photons.cpp) and the CUDA kernel (runtime/cuda/src/photons.cu) call the
// same functions, over
// the renderer's own closest-hit (prt/core/render.h), so both deposit the same photons up to
// floating-point rounding.
//
// Emission: each point light is covered by a cube; each face is a res x res grid of pixels and
// every pixel shoots `per_pixel` photons with directions jittered inside the pixel (thesis 5.4.1).
// Deviation from the thesis's P_photon = P / n: a pixel near a face's corner subtends less solid
// angle than one at its centre, so equal powers would make the light brighter towards the cube's
// corners. Each photon carries the power of the solid angle its pixel subtends instead,
// I dw = I (2/res)^2 / (1 + s^2 + t^2)^(3/2) at the pixel centre (s, t in [-1, 1] on the face),
// scaled so the 6 faces sum to exactly 4 pi: a light of color I emits 4 pi I in total, evenly.
//
// Area lights (issue 20): each area light (a parallelogram, scene_view.h) shoots as many photons as
// a point light, from points uniform over its area (stratified: a face_res x face_res grid of cells
// over the parallelogram, 6 x per_pixel jittered photons per cell) in directions cosine-distributed
// about its normal edge_u x edge_v (a one-sided Lambertian emitter; SCENE.md's default light faces
// down). Its power is pi I for a light of color I (intensity multiplied in): a Lambertian emitter of
// power P has the radiant intensity P / pi along its normal, so straight below it the light is as
// bright as a point light of color I, which is what the ray tracer's samples (I / samples^2 each)
// add up to there. Every photon carries pi I / N. Lights split the power as point lights do: every
// light shoots photons_per_light() photons, each with its share of that light's own power.
// The photon lights of a scene: the point lights (SceneView::lights[0, point_light_count)), then the
// area lights (not their point samples).
//
// Paths (thesis 5.4.1): only L S+ D is kept. A photon whose first hit is not specular is dropped
// (direct light, which the renderer shades itself); at a specular hit (reflectivity kr,
// transmissivity kt) it goes on with power x (kr + kt), reflected or refracted (refraction chosen
// with probability kt / (kr + kt), total internal reflection reflects); after at least one specular
// hit, a surface with a diffuse share d > 0 receives a deposit of the arriving power (the renderer
// multiplies by the albedo), and a photon still specular there goes on. The bounce limit
// (default 10) ends a path. Every bit of emitted power is accounted for (PhotonTally):
// emitted = direct + deposited + absorbed + escaped + truncated (physical power).
//
// Units: the renderer's point lights have no distance falloff (runtime/README.md: direct light is
// I cos theta). A deposit's power is multiplied by its squared distance d^2 from the light, the
// factor between the physical I cos theta / d^2 and the renderer's direct light there, so that the
// caustic map's irradiance and the renderer's direct light keep their physical ratio. An area
// light's photon is scaled likewise by its squared distance from its own point of emission.
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/render.h"
#include "prt/core/scene_view.h"
#include "prt/core/shading.h"

namespace prt::core {

/// One photon arriving at a diffuse surface after at least one specular hit, in the hit model's
/// local frame (40 bytes).
struct PhotonDeposit {
    float position[3];    ///< local frame
    std::uint32_t model;  ///< index into the scene's models
    float flux[3];        ///< arriving power (linear RGB) x squared distance to the light (see below)
    float normal[3];      ///< unit surface normal on the side the photon came from, local frame
};
static_assert(sizeof(PhotonDeposit) == 40);

/// Where the power went, per category (linear RGB); sums are exact up to rounding.
struct PhotonTally {
    double emitted[3] = {0, 0, 0};
    double direct[3] = {0, 0, 0};     ///< diffuse share at a first hit (not a caustic path)
    double deposited[3] = {0, 0, 0};  ///< diffuse share at L S+ D hits: what the caustic map holds x d
    double absorbed[3] = {0, 0, 0};   ///< 1 - d - kr - kt at every hit
    double escaped[3] = {0, 0, 0};    ///< left the scene
    double truncated[3] = {0, 0, 0};  ///< still specular at the bounce limit
    std::uint64_t photons = 0;        ///< photons shot
    std::uint64_t deposits = 0;       ///< deposit records
    std::uint64_t specular_hits = 0;
    std::uint64_t rays = 0;  ///< closest-hit queries (one per path segment)
};

/// What a kernel needs besides the scene.
struct PhotonShootParams {
    std::uint32_t face_res = 512;
    std::uint32_t per_pixel = 4;
    std::uint32_t max_bounces = 10;
    std::uint64_t seed = 1;
    /// 4 pi / (6 x sum over one face's pixels of the centre solid angle): makes emission sum to 4 pi.
    float solid_angle_norm = 1.0f;
};

PRT_HD PRT_INLINE std::uint64_t photons_per_light(const PhotonShootParams& p) {
    return 6ull * p.face_res * p.face_res * p.per_pixel;
}

/// splitmix64: a counter-based hash, so photon i's random numbers are the same on every backend.
PRT_HD PRT_INLINE std::uint64_t hash64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}
/// Uniform float in [0, 1) from the high 24 bits of a hash.
PRT_HD PRT_INLINE float unit_float(std::uint64_t h) {
    return static_cast<float>(h >> 40) * (1.0f / 16777216.0f);
}

/// thesis 5.4.1: photon `index` of a light: its direction (unit) and the fraction of the light's
/// color it carries (its solid angle, normalised).
PRT_HD inline void emit_photon(const PhotonShootParams& p, std::uint32_t light, std::uint64_t index,
                               Vec3& dir, float& solid_angle) {
    const std::uint64_t per_face = static_cast<std::uint64_t>(p.face_res) * p.face_res * p.per_pixel;
    const std::uint32_t face = static_cast<std::uint32_t>(index / per_face);
    const std::uint64_t rest = index - face * per_face;
    const std::uint64_t pixel = rest / p.per_pixel;
    const std::uint32_t px = static_cast<std::uint32_t>(pixel % p.face_res);
    const std::uint32_t py = static_cast<std::uint32_t>(pixel / p.face_res);
    const std::uint64_t h = hash64(p.seed ^ hash64((static_cast<std::uint64_t>(light) << 48) ^ index));
    const float inv_res = 1.0f / static_cast<float>(p.face_res);
    const float s = -1.0f + 2.0f * (static_cast<float>(px) + unit_float(h)) * inv_res;
    const float t = -1.0f + 2.0f * (static_cast<float>(py) + unit_float(hash64(h))) * inv_res;
    const float sc = -1.0f + (2.0f * static_cast<float>(px) + 1.0f) * inv_res;
    const float tc = -1.0f + (2.0f * static_cast<float>(py) + 1.0f) * inv_res;
    const float q = 1.0f + sc * sc + tc * tc;
    solid_angle =
        4.0f * inv_res * inv_res / (q * sqrtf(q)) * p.solid_angle_norm / static_cast<float>(p.per_pixel);
    // Faces +x, -x, +y, -y, +z, -z; (s, t) span the other two axes.
    const float sign = (face & 1u) ? -1.0f : 1.0f;
    Vec3 d;
    switch (face >> 1) {
        case 0:
            d = Vec3{sign, s, t};
            break;
        case 1:
            d = Vec3{t, sign, s};
            break;
        default:
            d = Vec3{s, t, sign};
            break;
    }
    dir = normalize(d);
}

/// The lights that shoot photons: the point lights, then the area lights (their samples in
/// SceneView::lights are the ray tracer's, not photon sources).
PRT_HD PRT_INLINE std::uint32_t photon_light_count(const SceneView& s) {
    return s.point_light_count + s.area_light_count;
}

/// Area lights (see the header comment): photon `index` of area light `a` (photon light number
/// `light`): its origin on the parallelogram, its unit direction (cosine-distributed about the
/// normal edge_u x edge_v) and the fraction of the light's color it carries (pi / photons).
PRT_HD inline void emit_area_photon(const PhotonShootParams& p, const AreaLight& a, std::uint32_t light,
                                    std::uint64_t index, Vec3& origin, Vec3& dir, float& share) {
    const std::uint64_t per_cell = 6ull * p.per_pixel;
    const std::uint64_t cell = index / per_cell;
    const std::uint32_t cx = static_cast<std::uint32_t>(cell % p.face_res);
    const std::uint32_t cy = static_cast<std::uint32_t>(cell / p.face_res);
    std::uint64_t h = hash64(p.seed ^ hash64((static_cast<std::uint64_t>(light) << 48) ^ index));
    const float inv_res = 1.0f / static_cast<float>(p.face_res);
    const float u = (static_cast<float>(cx) + unit_float(h)) * inv_res;
    h = hash64(h);
    const float v = (static_cast<float>(cy) + unit_float(h)) * inv_res;
    h = hash64(h);
    const float u1 = unit_float(h);
    h = hash64(h);
    origin = a.corner + a.edge_u * fminf(u, 1.0f) + a.edge_v * fminf(v, 1.0f);
    dir = cosine_direction(normalize(cross(a.edge_u, a.edge_v)), u1, unit_float(h));
    share = k_pi / static_cast<float>(photons_per_light(p));
}

/// Photon `index` of photon light `light` (photon_light_count()): where it starts, its unit
/// direction and its power (linear RGB).
PRT_HD inline void start_photon(const SceneView& s, const PhotonShootParams& p, std::uint32_t light,
                                std::uint64_t index, Vec3& origin, Vec3& dir, Vec3& flux) {
    float share = 0.0f;
    if (light < s.point_light_count) {
        emit_photon(p, light, index, dir, share);
        origin = s.lights[light].position;
        flux = s.lights[light].color * share;
    } else {
        const AreaLight& a = s.area_lights[light - s.point_light_count];
        emit_area_photon(p, a, light, index, origin, dir, share);
        flux = a.color * share;
    }
}

/// Per-thread tally in floats for kernels; the host one above sums in double.
struct PhotonTallyF {
    Vec3 emitted{0, 0, 0}, direct{0, 0, 0}, deposited{0, 0, 0}, absorbed{0, 0, 0}, escaped{0, 0, 0},
        truncated{0, 0, 0};
    std::uint32_t deposits = 0, specular_hits = 0, rays = 0;
};

/// thesis 5.4.1: traces photon `index` of photon light `light` (point lights, then area lights:
/// photon_light_count()) through the scene, calling
/// `deposit(const PhotonDeposit&)` at each L S+ D diffuse hit, and adds its fate to `tally`.
template <class DepositFn>
PRT_HD inline void trace_photon(const SceneView& s, const PhotonShootParams& p, std::uint32_t light,
                                std::uint64_t index, PhotonTallyF& tally, DepositFn&& deposit) {
    Vec3 source, dir, flux;
    start_photon(s, p, light, index, source, dir, flux);
    tally.emitted += flux;
    Ray ray{source, dir, k_inf, 0u};
    RayCounters counters;
    bool specular_seen = false;
    std::uint64_t h =
        hash64(p.seed * 0x632be59bd9b4e019ull ^ hash64(index ^ (static_cast<std::uint64_t>(light) << 50)));
    // Bounded: one closest-hit query per iteration, at most max_bounces + 1 iterations.
    for (std::uint32_t bounce = 0;; ++bounce) {
        SurfaceHit hit;
        ++tally.rays;
        if (!closest_hit_scene(s, ray, hit, counters)) {
            tally.escaped += flux;
            return;
        }
        const Material& m = s.materials[hit.material];
        float d = fmaxf(m.diffuse_reflectance, 0.0f), kr = fmaxf(m.reflectivity, 0.0f),
              kt = fmaxf(m.transmissivity, 0.0f);
        const float sum = d + kr + kt;
        if (sum > 1.0f) {  // the scene parser refuses this; keep the tally exact anyway
            d /= sum;
            kr /= sum;
            kt /= sum;
        }
        const Vec3 n = facing_normal(hit, ray);
        if (d > 0.0f) {
            if (specular_seen) {
                const ModelView& mv = s.models[hit.model];
                const Vec3 lp = mul_transpose(mv.rotation, hit.position - mv.offset) * mv.inv_scale;
                const Vec3 ln = normalize(mul_transpose(mv.rotation, n));
                PhotonDeposit dep;
                dep.position[0] = lp.x;
                dep.position[1] = lp.y;
                dep.position[2] = lp.z;
                dep.model = hit.model;
                // The renderer's point lights have no distance falloff (direct light I cos theta,
                // not I cos theta / d^2), so the deposit is stated in those units: times the squared
                // distance d from the light, caustic and direct light keep their physical ratio.
                const float d2 = length2(hit.position - source);
                dep.flux[0] = flux.x * d2;
                dep.flux[1] = flux.y * d2;
                dep.flux[2] = flux.z * d2;
                dep.normal[0] = ln.x;
                dep.normal[1] = ln.y;
                dep.normal[2] = ln.z;
                deposit(dep);
                ++tally.deposits;
                tally.deposited += flux * d;
            } else {
                tally.direct += flux * d;
            }
        }
        tally.absorbed += flux * fmaxf(0.0f, 1.0f - d - kr - kt);
        const float ks = kr + kt;
        if (!(ks > 0.0f)) return;
        if (bounce >= p.max_bounces) {
            tally.truncated += flux * ks;
            return;
        }
        ++tally.specular_hits;
        specular_seen = true;
        flux = flux * ks;
        h = hash64(h);
        bool refracted = false;
        if (kt > 0.0f && unit_float(h) * ks < kt) {
            const float ior = m.refractive_index > 0.0f ? m.refractive_index : 1.0f;
            const float eta = ray_inside(ray) ? ior : 1.0f / ior;
            Vec3 t;
            if (refract(ray.dir, n, eta, t)) {
                ray = leave_surface(hit, t, k_inf, ray.flags ^ k_ray_inside);
                refracted = true;
            }
        }
        if (!refracted) ray = leave_surface(hit, normalize(reflect(ray.dir, n)), k_inf, ray.flags);
    }
}

}  // namespace prt::core
