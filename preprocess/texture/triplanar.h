// PointRT preprocess: tri-planar texture projection (thesis 5.5, eq. 5.5), the math only (no image
// library), so tests can check it directly.
//
// thesis 5.5: three orthogonal axis-aligned planes with normals n_x, n_y, n_z each carry a tiled
// copy of the texture. A point p_i with normal n_i is projected onto each plane, the three
// projections sample the texture (c_x, c_y, c_z), and the point's color is the average of the three
// weighted by n_i . n_a (eq. 5.5). Two details the equation leaves open, fixed here:
//   - weights use |n_i . n_a|: a surface facing -z is as well served by the z plane as one facing
//     +z, and a signed dot product could make the denominator zero or negative;
//   - an exponent K ("sharpness") raises each weight to |n_i . n_a|^K; K = 1 is eq. 5.5 itself,
//     larger K narrows the blend zone where two projections overlap.
// A zero or non-finite normal gets equal weights (a defined color, never NaN).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace prt::pre::texture {

using D3 = std::array<double, 3>;
using D2 = std::array<double, 2>;

/// A linear RGB image, row 0 at the top, 3 floats per pixel (non-owning).
struct TextureView {
    const float* rgb = nullptr;
    std::uint32_t width = 0, height = 0;
};

/// Settings of one projection.
struct TriplanarParams {
    double scale = 1.0;      ///< world units per image repeat (> 0)
    double sharpness = 1.0;  ///< K: weight = |n . n_a|^K (thesis eq. 5.5: K = 1)
    D3 origin{0, 0, 0};      ///< model point where every plane's image has its corner
};

/// thesis eq. 5.5: the weights of the x, y and z planes for unit normal `n`, normalised to sum to
/// one: w_a = |n_a|^K / sum_b |n_b|^K. Computed relative to the largest component, so a large K
/// cannot underflow all three weights to zero.
inline D3 triplanar_weights(const D3& n, double sharpness) {
    const D3 a{std::fabs(n[0]), std::fabs(n[1]), std::fabs(n[2])};
    const double m = std::fmax(a[0], std::fmax(a[1], a[2]));
    if (!(m > 0.0) || !std::isfinite(m) || !std::isfinite(a[0] + a[1] + a[2]))
        return {1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
    D3 w{};
    double sum = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double r = a[i] / m;
        w[i] = sharpness == 1.0 ? r : std::pow(r, sharpness);  // the largest is exactly 1: sum >= 1
        sum += w[i];
    }
    for (double& x : w) x /= sum;
    return w;
}

/// The 2D coordinates (u, v) of `p` projected onto the plane whose normal is axis `axis`
/// (0 = x, 1 = y, 2 = z), relative to `origin`. v runs along +y on the x and z planes (so images
/// stand upright on walls) and along -z on the y plane (an image on the floor reads upright for a
/// viewer looking down -z); u completes a right-handed frame seen from the positive side (z plane:
/// u = x; x plane: u = -z; y plane: u = x).
inline D2 plane_coords(const D3& p, const D3& origin, int axis) {
    const double x = p[0] - origin[0], y = p[1] - origin[1], z = p[2] - origin[2];
    switch (axis) {
        case 0:
            return {-z, y};
        case 1:
            return {x, -z};
        default:
            return {x, y};
    }
}

/// Fractional part in [0, 1) (also for negative and huge values).
inline double wrap01(double s) {
    const double f = s - std::floor(s);
    return f < 1.0 ? f : 0.0;  // s = -1e-17 rounds to exactly 1
}

/// Bilinear sample of a tiled image at texture coordinates (s, t): one repeat per unit, s along the
/// image's columns, t upwards (t = 0 is the image's bottom edge, t = 1 its top). Texel centres sit
/// at ((i + 0.5) / width, 1 - (j + 0.5) / height), so a sample there returns the texel exactly.
/// Wraps at every edge.
inline D3 sample_wrap_bilinear(const TextureView& tex, double s, double t) {
    const double w = tex.width, h = tex.height;
    const double fx = wrap01(s) * w - 0.5;
    const double fy = wrap01(-t) * h - 0.5;  // rows run downwards
    const double x0f = std::floor(fx), y0f = std::floor(fy);
    const double ax = fx - x0f, ay = fy - y0f;
    // fx, fy lie in [-0.5, size - 0.5): x0f in [-1, size - 1].
    const std::uint32_t x0 = x0f < 0.0 ? tex.width - 1 : static_cast<std::uint32_t>(x0f);
    const std::uint32_t y0 = y0f < 0.0 ? tex.height - 1 : static_cast<std::uint32_t>(y0f);
    const std::uint32_t x1 = x0 + 1 == tex.width ? 0 : x0 + 1;
    const std::uint32_t y1 = y0 + 1 == tex.height ? 0 : y0 + 1;
    auto texel = [&](std::uint32_t x, std::uint32_t y) {
        const float* p = tex.rgb + (static_cast<std::size_t>(y) * tex.width + x) * 3;
        return D3{p[0], p[1], p[2]};
    };
    const D3 c00 = texel(x0, y0), c10 = texel(x1, y0), c01 = texel(x0, y1), c11 = texel(x1, y1);
    D3 c{};
    for (int i = 0; i < 3; ++i) {
        // Exact texel value when ax = ay = 0 (the other terms are multiplied by zero).
        c[i] = (c00[i] * (1.0 - ax) + c10[i] * ax) * (1.0 - ay) + (c01[i] * (1.0 - ax) + c11[i] * ax) * ay;
    }
    return c;
}

/// thesis eq. 5.5: the tri-planar color of point `p` with normal `n`. `tex[a]` is the image on the
/// plane with normal axis a (the three may be the same image).
inline D3 triplanar_color(const TextureView (&tex)[3], const D3& p, const D3& n,
                          const TriplanarParams& params) {
    const D3 w = triplanar_weights(n, params.sharpness);
    D3 c{0, 0, 0};
    for (int a = 0; a < 3; ++a) {
        if (w[a] == 0.0) continue;  // skips the texture fetch where a plane does not contribute
        const D2 uv = plane_coords(p, params.origin, a);
        const D3 s = sample_wrap_bilinear(tex[a], uv[0] / params.scale, uv[1] / params.scale);
        for (int i = 0; i < 3; ++i) c[i] += w[a] * s[i];
    }
    return c;
}

/// The linear value of an sRGB-encoded (IEC 61966-2-1) component in [0, 1].
inline double srgb_to_linear(double c) {
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

/// The linear value of an 8-bit sRGB-encoded component.
inline double srgb8_to_linear(std::uint8_t v) {
    return srgb_to_linear(v / 255.0);
}

/// sRGB encoding of a linear value, clamped to [0, 1], rounded to 8 bits: point colors are stored
/// display-encoded (the renderer decodes them, prt/core/shading.h). Equal to round(255 * encode(c))
/// with encode(c) = 1.055 c^(1/2.4) - 0.055 (12.92 c below 0.0031308): the number of rounding
/// thresholds decode((k + 0.5) / 255), k = 0..254, at or below c. A binary search over them costs
/// 8 comparisons instead of a pow(): baking 2M points took 0.58 s instead of 1.1-1.4 s (same
/// bytes; 2 shared cores of the dev machine).
inline std::uint8_t linear_to_srgb8(double c) {
    if (!(c > 0.0)) return 0;  // also NaN
    if (c >= 1.0) return 255;
    static const std::array<double, 255> thresholds = [] {
        std::array<double, 255> t{};
        for (int k = 0; k < 255; ++k) t[k] = srgb_to_linear((k + 0.5) / 255.0);
        return t;
    }();
    std::size_t lo = 0, hi = thresholds.size();  // count of thresholds <= c lies in [lo, hi]
    while (lo < hi) {
        const std::size_t mid = (lo + hi) / 2;
        if (thresholds[mid] <= c)
            lo = mid + 1;
        else
            hi = mid;
    }
    return static_cast<std::uint8_t>(lo);
}

}  // namespace prt::pre::texture
