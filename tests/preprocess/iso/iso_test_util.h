// Shared helpers of the ISO tests: point sets from prt-synth's analytic shapes, and the independent
// references: k-NN radii by brute force, eq. 4.1-4.3 evaluated directly over ALL points in double
// precision (truncated as prt-iso documents, and untruncated in log space), exact ray hits with the
// analytic sphere and torus.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <vector>

#include "analytic.h"
#include "d3_math.h"
#include "iso_build.h"
#include "iso_pool.h"
#include "prt/core/iso.h"
#include "synth.h"

namespace prt::iso_test {

using test::D3;
using test::d3;
using test::dot3;
using test::norm3;

inline D3 sub3(const D3& a, const D3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
/// Angle between two vectors in degrees.
inline double angle_deg(const D3& a, const D3& b) {
    const double c = dot3(a, b) / (norm3(a) * norm3(b));
    return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

/// Points in the local frame (the shapes are centred at the origin: local = world).
struct PointSet {
    std::vector<pool::Float3> positions, normals;
    std::vector<float> radii;
    std::vector<pool::Rgba8> colors;
    synth::Shape shape;

    iso::BuildInput input(bool with_radii = false) const {
        iso::BuildInput in;
        in.positions = positions;
        in.normals = normals;
        if (with_radii) in.radii = radii;
        in.colors = colors;
        return in;
    }
};

/// prt-synth's sampling of a shape (R2 sequence unless `sampling`, exact normals), optionally with
/// noise along the normal and colors from the normals.
inline PointSet synth_points(const synth::Shape& shape, std::uint64_t count, double noise = 0.0,
                             bool colors = false, synth::Sampling sampling = synth::Sampling::r2) {
    synth::SynthOptions o;
    o.shape = shape;
    o.count = count;
    o.noise = noise;
    o.sampling = sampling;
    o.colors = colors ? synth::ColorMode::normal : synth::ColorMode::none;
    o.threads = 2;
    const synth::SynthResult r = synth::synthesize(o);
    PointSet s;
    s.shape = shape;
    for (std::size_t i = 0; i < r.cloud.positions.size(); ++i) {
        const auto& p = r.cloud.positions[i];
        s.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
        s.normals.push_back(r.cloud.normals[i]);
    }
    s.colors = r.cloud.colors;
    return s;
}

inline synth::Shape sphere_shape(double radius = 1.0) {
    synth::Shape s;
    s.kind = synth::ShapeKind::sphere;
    s.sphere.radius = radius;
    return s;
}

inline synth::Shape torus_shape(double major = 1.0, double minor = 0.4) {
    synth::Shape s;
    s.kind = synth::ShapeKind::torus;
    s.torus.major_radius = major;
    s.torus.minor_radius = minor;
    return s;
}

/// Brute force: distance from every point to its k-th nearest other point, then prt-radii's clamp
/// (radii above clamp x median become clamp x median).
inline std::vector<double> brute_knn_radii(const PointSet& s, std::uint32_t k, double clamp) {
    const std::size_t n = s.positions.size();
    std::vector<double> r(n), d(n);
    for (std::size_t i = 0; i < n; ++i) {
        const D3 p = d3(s.positions[i]);
        std::size_t m = 0;
        for (std::size_t j = 0; j < n; ++j)
            if (j != i) d[m++] = norm3(sub3(d3(s.positions[j]), p));
        std::nth_element(d.begin(), d.begin() + (k - 1), d.begin() + m);
        r[i] = d[k - 1];
    }
    std::vector<double> sorted(r);
    std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
    const double limit = clamp * sorted[n / 2];
    if (clamp > 0)
        for (double& v : r) v = std::min(v, limit);
    return r;
}

/// The value of eq. 4.1-4.3 at Q: f, the weighted normal (eq. 4.2, normalized here) and color.
struct Reference {
    double f = 0;
    D3 n{0, 0, 0};
    D3 color{0, 0, 0};
    std::size_t counted = 0;  ///< points that contributed
};

/// eq. 4.1-4.3 over every point with |Q - p_i| <= support x sigma_i, literally: w_i =
/// exp(-|Q - p_i|^2 / (2 sigma_i^2)) / sqrt(2 pi sigma_i^2), p = sum w p / sum w, n = sum w n / sum w,
/// f = (Q - p) . n. counted = 0 when no point is within its support.
inline Reference reference_truncated(const PointSet& s, const std::vector<double>& sigma, double support,
                                     const D3& q) {
    Reference r;
    double w = 0;
    D3 p{0, 0, 0}, n{0, 0, 0}, c{0, 0, 0};
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const D3 pi = d3(s.positions[i]);
        const double d = norm3(sub3(q, pi));
        if (d > support * sigma[i]) continue;
        const double wi = std::exp(-d * d / (2 * sigma[i] * sigma[i])) /
                          std::sqrt(2 * std::numbers::pi * sigma[i] * sigma[i]);
        w += wi;
        D3 ni = d3(s.normals[i]);
        const double len = norm3(ni);
        for (int a = 0; a < 3; ++a) {
            p[a] += wi * pi[a];
            n[a] += wi * ni[a] / len;
        }
        if (!s.colors.empty()) {
            c[0] += wi * s.colors[i].r, c[1] += wi * s.colors[i].g, c[2] += wi * s.colors[i].b;
        }
        ++r.counted;
    }
    if (r.counted == 0) return r;
    for (int a = 0; a < 3; ++a) p[a] /= w, n[a] /= w, c[a] /= w;
    r.f = dot3(sub3(q, p), n);
    const double len = norm3(n);
    for (int a = 0; a < 3; ++a) r.n[a] = n[a] / len;
    r.color = c;
    return r;
}

/// eq. 4.1-4.3 over every point, no truncation (weights divided by the largest one, in log space,
/// so they cannot all underflow far from the points).
inline Reference reference_full(const PointSet& s, const std::vector<double>& sigma, const D3& q) {
    const std::size_t n = s.positions.size();
    std::vector<double> lw(n);
    double lmax = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) {
        const double d = norm3(sub3(q, d3(s.positions[i])));
        lw[i] = -d * d / (2 * sigma[i] * sigma[i]) - std::log(std::sqrt(2 * std::numbers::pi) * sigma[i]);
        lmax = std::max(lmax, lw[i]);
    }
    Reference r;
    double w = 0;
    D3 p{0, 0, 0}, nn{0, 0, 0};
    for (std::size_t i = 0; i < n; ++i) {
        const double wi = std::exp(lw[i] - lmax);
        const D3 pi = d3(s.positions[i]);
        const D3 ni = d3(s.normals[i]);
        const double len = norm3(ni);
        w += wi;
        for (int a = 0; a < 3; ++a) p[a] += wi * pi[a], nn[a] += wi * ni[a] / len;
    }
    for (int a = 0; a < 3; ++a) p[a] /= w, nn[a] /= w;
    r.f = dot3(sub3(q, p), nn);
    const double len = norm3(nn);
    for (int a = 0; a < 3; ++a) r.n[a] = nn[a] / len;
    r.counted = n;
    return r;
}

/// Exact first hit of the ray o + t d (d unit) with a sphere of radius R at the origin, t >= 0.
inline bool sphere_hit(const D3& o, const D3& d, double R, double& t) {
    const double b = dot3(o, d), c = dot3(o, o) - R * R;
    const double disc = b * b - c;
    if (disc < 0) return false;
    const double s = std::sqrt(disc);
    t = -b - s;
    if (t < 0) t = -b + s;
    return t >= 0;
}

/// First hit of a ray (d unit) from outside an analytic shape whose signed distance is a true
/// Euclidean distance (sphere, torus): sphere tracing in double. Returns the hit t, or false.
inline bool analytic_hit(const synth::Shape& shape, const D3& o, const D3& d, double t_max, double& t) {
    t = 0;
    for (int i = 0; i < 100000; ++i) {
        const D3 p{o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        const double sd = synth::signed_distance(shape, p);
        if (sd < 1e-12) return true;
        t += sd;
        if (t > t_max) return false;
    }
    return false;
}

/// A pinhole camera at `eye` looking at the origin; unit ray direction of pixel (x, y) of w x h,
/// vertical field of view `fov_deg`.
struct Camera {
    D3 eye, fwd, right, up;
    double tan_half;
    Camera(D3 e, double fov_deg) : eye(e) {
        fwd = {-e[0], -e[1], -e[2]};
        const double l = norm3(fwd);
        for (double& v : fwd) v /= l;
        D3 world_up{0, 1, 0};
        if (std::abs(dot3(world_up, fwd)) > 0.99) world_up = {0, 0, 1};
        right = {fwd[1] * world_up[2] - fwd[2] * world_up[1], fwd[2] * world_up[0] - fwd[0] * world_up[2],
                 fwd[0] * world_up[1] - fwd[1] * world_up[0]};
        const double rl = norm3(right);
        for (double& v : right) v /= rl;
        up = {right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
              right[0] * fwd[1] - right[1] * fwd[0]};
        tan_half = std::tan(fov_deg * std::numbers::pi / 360.0);
    }
    D3 dir(double x, double y, int w, int h) const {
        const double sx = (2 * (x + 0.5) / w - 1) * tan_half * w / h;
        const double sy = (1 - 2 * (y + 0.5) / h) * tan_half;
        D3 d{fwd[0] + sx * right[0] + sy * up[0], fwd[1] + sx * right[1] + sy * up[1],
             fwd[2] + sx * right[2] + sy * up[2]};
        const double l = norm3(d);
        for (double& v : d) v /= l;
        return d;
    }
};

inline core::Vec3 vf(const D3& a) {
    return core::Vec3{float(a[0]), float(a[1]), float(a[2])};
}

}  // namespace prt::iso_test
