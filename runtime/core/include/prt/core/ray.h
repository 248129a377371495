// PointRT core: rays and the seamless front/back flag (thesis 3.6).
#pragma once

#include <cstdint>

#include "prt/core/math.h"

namespace prt::core {

/// Ray flag bits.
enum RayFlags : std::uint32_t {
    /// thesis 3.6 (seamless ray tracing): the ray travels inside an object, so it expects to hit
    /// back faces (dot(dir, normal) > 0) and ignores front faces. Clear for rays that start outside:
    /// they expect front faces and ignore back faces. Reflection keeps the flag, refraction flips it.
    /// This replaces any "minimum distance between intersections" epsilon.
    k_ray_inside = 1u << 0,
};

/// A ray in some frame (render frame or a model's local frame). `dir` need not be unit length in a
/// model's local frame: the ray parameter t is the same in every frame (t = distance in the
/// render frame, where dir is unit).
struct Ray {
    Vec3 origin;
    Vec3 dir;
    float t_max;          ///< hits at t >= t_max are ignored (the light's distance for shadow rays)
    std::uint32_t flags;  ///< RayFlags
    /// The surface point a secondary or shadow ray leaves: model index (k_no_model for primary
    /// rays), primitive and its (u, v). Only surfaces whose faces carry no orientation (patch pools
    /// not marked oriented) need it: there the seamless flag cannot tell the start point from a
    /// real hit, so roots within a tiny parameter distance of it are skipped (seed 002, 5.6).
    std::uint32_t from_model = 0xffffffffu;
    std::uint32_t from_prim = 0;
    float from_u = 0.0f, from_v = 0.0f;
};

/// Ray::from_model of rays that leave no surface.
inline constexpr std::uint32_t k_no_model = 0xffffffffu;

PRT_HD PRT_INLINE Vec3 ray_at(const Ray& r, float t) {
    return r.origin + r.dir * t;
}
PRT_HD PRT_INLINE bool ray_inside(const Ray& r) {
    return (r.flags & k_ray_inside) != 0;
}

/// thesis 3.6: whether a surface with normal `n` (as stored, outward) met by direction `d` is the
/// kind of face the ray expects: front (dot < 0) for outside rays, back (dot > 0) for inside rays.
/// Grazing hits (dot == 0) are never accepted.
PRT_HD PRT_INLINE bool face_expected(float d_dot_n, bool inside) {
    return inside ? d_dot_n > 0.0f : d_dot_n < 0.0f;
}

}  // namespace prt::core
