// PointRT core: ray casting for callers' own rays (issue 18: the library's Backend::cast and
// Backend::occluded, the public API prt/pointrt.h and the Python module). One ray of a batch is
// read from the caller's arrays (world frame, float or double, any stride), checked, moved into the
// render frame in double (as RenderScene converts cameras: DESIGN.md, numerical robustness), and
// traced by the renderer's own closest_hit / occluded walks over every surface (render.h).
//
// Convention (Embree's and Open3D's): a ray is origin + t * direction with t in [t_min, t_max), t in
// units of the direction's length (the direction need not be unit). The core traces unit
// directions from the point at t_min; t is converted back on the way out.
#pragma once

#include <cstddef>
#include <cstdint>

#include "prt/core/render.h"

namespace prt::core {

/// No element (ISO, bricked splats, misses): CastHit::element.
inline constexpr std::uint32_t k_no_element = 0xffffffffu;

/// A caller's ray batch as the kernels read it: the world-frame arrays and the render frame's
/// origin. Pointers are host or device memory, as the backend runs; strides in bytes.
struct CastRays {
    std::size_t count = 0;
    const void* origins = nullptr;  ///< 3 values per ray
    const void* directions = nullptr;
    std::size_t origin_stride = 0, direction_stride = 0;  ///< bytes between rays
    std::uint32_t origins_f64 = 0, directions_f64 = 0;    ///< double (1) or float (0) values
    const float* t_min = nullptr;                         ///< per ray, or null: t_min_value
    const float* t_max = nullptr;                         ///< per ray, or null: t_max_value
    std::size_t t_min_stride = 4, t_max_stride = 4;
    float t_min_value = 0.0f, t_max_value = 3.402823466e38f;
    double offset[3] = {0, 0, 0};  ///< world position of the render frame's origin
};

/// Where the answers go (structure of arrays, each optional: null is not written).
struct CastOutputs {
    std::uint8_t* hit = nullptr;      ///< 1 hit, 0 miss or invalid
    std::uint8_t* valid = nullptr;    ///< 0 for NaN/infinite input or a zero-length direction
    float* t = nullptr;               ///< +inf for misses
    float* position = nullptr;        ///< 3 per ray, world frame (render frame + offset, in double)
    float* normal = nullptr;          ///< 3 per ray, unit, outward as stored (world = render frame axes)
    float* color = nullptr;           ///< 3 per ray, the point colour (display-encoded, [0, 1]); 1 without
    std::int32_t* model = nullptr;    ///< model index, -1 for misses
    std::int64_t* element = nullptr;  ///< source point (splats, MLS), patch (patches), else -1
};

/// One ray read from a CastRays and prepared for the core.
struct CastRay {
    Ray ray;           ///< render frame, unit direction, starting at t_min
    double t_min = 0;  ///< caller's units
    double scale = 1;  ///< caller's t per core t: 1 / |direction|
    bool valid = false;
};

template <class T>
PRT_HD PRT_INLINE void cast_load3(const void* base, std::size_t stride, std::size_t i, double v[3]) {
    const T* p = reinterpret_cast<const T*>(static_cast<const unsigned char*>(base) + i * stride);
    v[0] = static_cast<double>(p[0]);
    v[1] = static_cast<double>(p[1]);
    v[2] = static_cast<double>(p[2]);
}

PRT_HD PRT_INLINE bool cast_finite(double x) {
    return x - x == 0.0;  // false for NaN and +-inf (no <cmath> needed on the device)
}

/// Reads and checks ray i: finite origin and direction, a non-zero direction, t_min finite and
/// >= 0, t_max not NaN. An empty interval (t_max <= t_min) is valid and misses.
PRT_HD inline CastRay cast_read(const CastRays& b, std::size_t i) {
    CastRay out;
    double o[3], d[3];
    if (b.origins_f64)
        cast_load3<double>(b.origins, b.origin_stride, i, o);
    else
        cast_load3<float>(b.origins, b.origin_stride, i, o);
    if (b.directions_f64)
        cast_load3<double>(b.directions, b.direction_stride, i, d);
    else
        cast_load3<float>(b.directions, b.direction_stride, i, d);
    const double t0 = b.t_min ? *reinterpret_cast<const float*>(
                                    reinterpret_cast<const unsigned char*>(b.t_min) + i * b.t_min_stride)
                              : b.t_min_value;
    const double t1 = b.t_max ? *reinterpret_cast<const float*>(
                                    reinterpret_cast<const unsigned char*>(b.t_max) + i * b.t_max_stride)
                              : b.t_max_value;
    const double len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    bool ok = cast_finite(o[0]) && cast_finite(o[1]) && cast_finite(o[2]) && cast_finite(len2) &&
              len2 > 0.0 && cast_finite(t0) && t0 >= 0.0 && !(t1 != t1);
    if (!ok) {
        out.ray = Ray{Vec3{0, 0, 0}, Vec3{0, 0, 1}, 0.0f, 0u};
        return out;
    }
    const double len = sqrt(len2);
    const double inv = 1.0 / len;
    // The start point at t_min, in the render frame (double, then float once).
    const double s[3] = {o[0] + d[0] * t0 - b.offset[0], o[1] + d[1] * t0 - b.offset[1],
                         o[2] + d[2] * t0 - b.offset[2]};
    const double span = t1 > t0 ? (t1 - t0) * len : 0.0;  // core units: distance
    const float t_max = span < 3.0e38 ? static_cast<float>(span) : 3.402823466e38f;
    out.ray = Ray{
        Vec3{static_cast<float>(s[0]), static_cast<float>(s[1]), static_cast<float>(s[2])},
        Vec3{static_cast<float>(d[0] * inv), static_cast<float>(d[1] * inv), static_cast<float>(d[2] * inv)},
        t_max, 0u};
    out.t_min = t0;
    out.scale = inv;
    out.valid = true;
    return out;
}

/// The closest hit of one ray over every model (closest_hit_scene()'s walk, keeping the element:
/// the source point of splats and MLS, the patch of patches).
template <std::uint32_t K = k_mask_all>
PRT_HD inline bool cast_closest(const SceneView& s, const Ray& r, ModelHit& best_hit, std::uint32_t& model,
                                std::uint32_t& element, RayCounters& c) {
    float best = r.t_max;
    bool found = false;
    for_each_surface<K>(s, r, [&](auto surface, const ModelRay& q) {
        ModelHit cand;
        if (closest_on(surface, s, q, best, cand, c) && (cand.t < best || !found)) {
            best = cand.t;
            best_hit = cand;
            model = q.model;
            element = decltype(surface)::kind == SurfaceKind::patches ? cand.prim : cand.point;
            found = true;
        }
        return false;
    });
    return found;
}

/// Casts ray i of `b` and writes its answers into `out` (closest hits).
template <std::uint32_t K = k_mask_all>
PRT_HD inline void cast_one(const SceneView& s, const CastRays& b, const CastOutputs& out, std::size_t i,
                            RayCounters& c) {
    const CastRay cr = cast_read(b, i);
    ModelHit h;
    std::uint32_t model = 0, element = k_no_element;
    const bool hit = cr.valid && cast_closest<K>(s, cr.ray, h, model, element, c);
    if (out.hit) out.hit[i] = hit ? 1 : 0;
    if (out.valid) out.valid[i] = cr.valid ? 1 : 0;
    const float inf = k_inf;
    if (out.t) out.t[i] = hit ? static_cast<float>(cr.t_min + static_cast<double>(h.t) * cr.scale) : inf;
    Vec3 n{0, 0, 0}, col{0, 0, 0};
    double p[3] = {inf, inf, inf};
    if (hit) {
        const ModelView& mv = s.models[model];
        n = normalize(mv.rotation * h.normal);
        col = h.color;
        const Vec3 pr = ray_at(cr.ray, h.t);
        p[0] = static_cast<double>(pr.x) + b.offset[0];
        p[1] = static_cast<double>(pr.y) + b.offset[1];
        p[2] = static_cast<double>(pr.z) + b.offset[2];
    }
    if (out.position) {
        out.position[i * 3 + 0] = static_cast<float>(p[0]);
        out.position[i * 3 + 1] = static_cast<float>(p[1]);
        out.position[i * 3 + 2] = static_cast<float>(p[2]);
    }
    if (out.normal) {
        out.normal[i * 3 + 0] = n.x;
        out.normal[i * 3 + 1] = n.y;
        out.normal[i * 3 + 2] = n.z;
    }
    if (out.color) {
        out.color[i * 3 + 0] = col.x;
        out.color[i * 3 + 1] = col.y;
        out.color[i * 3 + 2] = col.z;
    }
    if (out.model) out.model[i] = hit ? static_cast<std::int32_t>(model) : -1;
    if (out.element)
        out.element[i] = hit && element != k_no_element ? static_cast<std::int64_t>(element) : -1;
}

/// Whether anything blocks ray i of `b` in [t_min, t_max) (any hit, occluded()); invalid rays: 0.
template <std::uint32_t K = k_mask_all>
PRT_HD inline void occluded_one(const SceneView& s, const CastRays& b, std::uint8_t* flags,
                                std::uint8_t* valid, std::size_t i, RayCounters& c) {
    const CastRay cr = cast_read(b, i);
    const bool blocked = cr.valid && cr.ray.t_max > 0.0f && occluded<K>(s, cr.ray, c);
    if (flags) flags[i] = blocked ? 1 : 0;
    if (valid) valid[i] = cr.valid ? 1 : 0;
}

}  // namespace prt::core
