// PointRT core: the pinhole camera and the Z-order mapping of rays to threads (thesis 2.3).
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/ray.h"

namespace prt::core {

/// A pinhole camera in the render frame. `right` and `up` are pre-scaled so that pixel (x, y) of a
/// width x height image looks along forward + (2u-1) right + (1-2v) up, u = (x+0.5)/width.
struct PinholeCamera {
    Vec3 position;
    Vec3 forward;  ///< unit
    Vec3 right;    ///< length tan(fov_y/2) * aspect
    Vec3 up;       ///< length tan(fov_y/2)
};

/// Builds a camera looking from `position` at `target`; `up_hint` need not be orthogonal to the
/// view direction. Degenerate input (target == position, up parallel to the view) still gives a
/// valid orthonormal camera.
PRT_HD inline PinholeCamera make_pinhole(Vec3 position, Vec3 target, Vec3 up_hint, float fov_y_degrees,
                                         std::uint32_t width, std::uint32_t height) {
    PinholeCamera c;
    c.position = position;
    c.forward = normalize_or(target - position, Vec3{0, 0, -1});
    Vec3 right = cross(c.forward, up_hint);
    if (!(length2(right) > 1e-12f)) {
        // up parallel to the view direction: pick any perpendicular axis
        right = cross(c.forward, fabsf(c.forward.y) < 0.9f ? Vec3{0, 1, 0} : Vec3{1, 0, 0});
    }
    right = normalize(right);
    const Vec3 up = cross(right, c.forward);
    const float fov = clampf(fov_y_degrees, 1e-3f, 179.0f) * (k_pi / 180.0f);
    const float half = tanf(0.5f * fov);
    const float aspect = height > 0 ? static_cast<float>(width) / static_cast<float>(height) : 1.0f;
    c.right = right * (half * aspect);
    c.up = up * half;
    return c;
}

/// The primary ray through pixel (x, y) (row 0 at the top) at sub-pixel offset (sx, sy) in [0,1).
PRT_HD PRT_INLINE Ray primary_ray(const PinholeCamera& c, std::uint32_t x, std::uint32_t y,
                                  std::uint32_t width, std::uint32_t height, float sx = 0.5f,
                                  float sy = 0.5f) {
    const float u = (static_cast<float>(x) + sx) / static_cast<float>(width);
    const float v = (static_cast<float>(y) + sy) / static_cast<float>(height);
    const Vec3 d = c.forward + c.right * (2.0f * u - 1.0f) + c.up * (1.0f - 2.0f * v);
    return Ray{c.position, normalize(d), k_inf, 0u};
}

/// The angle a pixel subtends at the image centre (radians): a ray's footprint grows by this much
/// per unit of distance (level of detail, RenderParams::lod_spread).
PRT_HD PRT_INLINE float pixel_angle(const PinholeCamera& c, std::uint32_t height) {
    return height > 0 ? 2.0f * length(c.up) / static_cast<float>(height) : 0.0f;
}

/// thesis 2.3: de-interleaves the even bits of a 32-bit index (Morton / Z-order decode).
PRT_HD PRT_INLINE std::uint32_t morton_compact(std::uint32_t v) {
    v &= 0x55555555u;
    v = (v | (v >> 1)) & 0x33333333u;
    v = (v | (v >> 2)) & 0x0f0f0f0fu;
    v = (v | (v >> 4)) & 0x00ff00ffu;
    v = (v | (v >> 8)) & 0x0000ffffu;
    return v;
}

/// thesis 2.3: the pixel (x, y) of the i-th thread along a Z-order curve: x = even bits, y = odd
/// bits, so the 32 threads of a warp cover an 8x4 block of neighbouring (coherent) rays.
PRT_HD PRT_INLINE void zorder_decode(std::uint32_t i, std::uint32_t& x, std::uint32_t& y) {
    x = morton_compact(i);
    y = morton_compact(i >> 1);
}

}  // namespace prt::core
