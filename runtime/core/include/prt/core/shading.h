// PointRT core: shading helpers: reflection and refraction directions (thesis 7.2, with the
// standard Snell's-law form where the extracted formula is garbled), Lambert + Phong terms
// (thesis 5.2), the background, color encoding, tone mapping and gamma.
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/scene_view.h"

namespace prt::core {

/// thesis 7.2, eq. 7.1: mirror direction of `d` about the unit normal `n`: r = d - 2 (n.d) n.
PRT_HD PRT_INLINE Vec3 reflect(Vec3 d, Vec3 n) {
    return d - n * (2.0f * dot(n, d));
}

/// thesis 7.2, eq. 7.2 (Snell's law, standard vector form): refracts unit `d` through a surface
/// whose unit normal `n` faces against d (dot(d, n) <= 0), going from index n1 to n2 with
/// eta = n1 / n2. Returns false on total internal reflection (then `t` is unchanged).
PRT_HD PRT_INLINE bool refract(Vec3 d, Vec3 n, float eta, Vec3& t) {
    const float cos_i = fminf(-dot(d, n), 1.0f);
    const float sin2_t = eta * eta * fmaxf(0.0f, 1.0f - cos_i * cos_i);
    if (sin2_t > 1.0f) return false;  // total internal reflection
    const float cos_t = sqrtf(1.0f - sin2_t);
    t = normalize_or(d * eta + n * (eta * cos_i - cos_t), d);
    return true;
}

/// sRGB-encoded component in [0,1] to linear.
PRT_HD PRT_INLINE float srgb_to_linear(float c) {
    return c <= 0.04045f ? c * (1.0f / 12.92f) : powf((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}
PRT_HD PRT_INLINE Vec3 srgb_to_linear(Vec3 c) {
    return {srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)};
}

/// The background seen along unit direction `d` (render frame = world orientation, +y up):
/// a latitude-longitude image (bilinear, u wraps) or the constant color, times the intensity.
/// Image convention (tests/runtime/environment_test.cpp): column u = 0.5 + atan2(d.x, -d.z) / 2 pi
/// (the image centre straight ahead along -z, +x to its right), row v = acos(d.y) / pi (row 0 = +y).
PRT_HD inline Vec3 background(const EnvironmentView& env, Vec3 d) {
    if (env.image == nullptr || env.width == 0 || env.height == 0) return env.color * env.intensity;
    // A non-finite direction has no texel (and float-to-int of NaN is undefined): no radiance.
    if (!is_finite(d)) return Vec3{0, 0, 0};
    const float u = 0.5f + atan2f(d.x, -d.z) * (0.5f / k_pi);
    const float v = acosf(clampf(d.y, -1.0f, 1.0f)) * (1.0f / k_pi);
    const float fx = u * static_cast<float>(env.width) - 0.5f;
    const float fy =
        clampf(v * static_cast<float>(env.height) - 0.5f, 0.0f, static_cast<float>(env.height - 1));
    const float x0f = floorf(fx), y0f = floorf(fy);
    const float ax = fx - x0f, ay = fy - y0f;
    const int w = static_cast<int>(env.width), h = static_cast<int>(env.height);
    int x0 = static_cast<int>(x0f) % w;
    if (x0 < 0) x0 += w;
    const int x1 = (x0 + 1) % w;
    const int y0 = static_cast<int>(y0f) < h ? static_cast<int>(y0f) : h - 1;
    const int y1 = y0 + 1 < h ? y0 + 1 : h - 1;
    auto px = [&](int x, int y) {
        const float* p =
            env.image + (static_cast<std::uint64_t>(y) * env.width + static_cast<std::uint32_t>(x)) * 3u;
        return Vec3{p[0], p[1], p[2]};
    };
    const Vec3 top = px(x0, y0) * (1.0f - ax) + px(x1, y0) * ax;
    const Vec3 bottom = px(x0, y1) * (1.0f - ax) + px(x1, y1) * ax;
    const Vec3 c = top * (1.0f - ay) + bottom * ay;
    return (is_finite(c) ? c : Vec3{0, 0, 0}) * env.intensity;
}

/// thesis 5.2: the Lambert + Phong contribution of one unoccluded light at a surface point with
/// shading normal `n` (facing the viewer), unit light direction `l`, viewing direction `d`.
PRT_HD PRT_INLINE Vec3 lambert_phong(const Material& m, Vec3 base, Vec3 n, Vec3 l, Vec3 d, Vec3 light_color) {
    const float ndl = dot(n, l);
    if (!(ndl > 0.0f)) return Vec3{0, 0, 0};
    const Vec3 r = n * (2.0f * ndl) - l;  // l mirrored about n
    const float rv = fmaxf(0.0f, -dot(r, d));
    const float spec = rv > 0.0f ? powf(rv, m.specular_exponent) : 0.0f;
    return light_color * (m.diffuse * base * ndl + m.specular * spec);
}

/// Tone mapping (after exposure) to [0,1], then gamma encoding.
PRT_HD PRT_INLINE float tone_map(float c, ToneMap op) {
    c = fmaxf(c, 0.0f);
    switch (op) {
        case ToneMap::reinhard:
            c = c / (1.0f + c);
            break;
        case ToneMap::aces:
            c = (c * (2.51f * c + 0.03f)) / (c * (2.43f * c + 0.59f) + 0.14f);
            break;
        case ToneMap::clamp:
            break;
    }
    return clampf(c, 0.0f, 1.0f);
}

/// Linear radiance to display-encoded [0,1]: exposure, tone map, gamma.
PRT_HD PRT_INLINE Vec3 encode_display(Vec3 c, const RenderParams& p) {
    const float g = p.gamma > 0.0f ? 1.0f / p.gamma : 1.0f;
    const Vec3 e = c * p.exposure;
    return Vec3{powf(tone_map(e.x, p.tone_map), g), powf(tone_map(e.y, p.tone_map), g),
                powf(tone_map(e.z, p.tone_map), g)};
}

/// Packs display-encoded [0,1] RGB into 8-bit RGBA (alpha 255).
PRT_HD PRT_INLINE std::uint32_t pack_rgba8(Vec3 c) {
    const auto q = [](float v) { return static_cast<std::uint32_t>(clampf(v, 0.0f, 1.0f) * 255.0f + 0.5f); };
    return q(c.x) | (q(c.y) << 8) | (q(c.z) << 16) | (255u << 24);
}

}  // namespace prt::core
