// Test-only reference for the disk/box overlap, written independently of preprocess/splat/disk_box.h:
// it builds the polygon (plane n box) explicitly from the plane's crossings of the 12 box edges,
// orders it by angle in a 2D frame of the plane, and measures the distance from the disk centre to
// that polygon (inside test + distance to its edges). Double precision throughout.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace prt::test {

/// Distance from c to (plane through c with normal n) n (box [lo, hi]); +inf when the plane misses.
inline double reference_plane_box_distance(const double c_in[3], const double n_in[3], const double lo[3],
                                           const double hi[3]) {
    const double len = std::sqrt(n_in[0] * n_in[0] + n_in[1] * n_in[1] + n_in[2] * n_in[2]);
    const std::array<double, 3> n{n_in[0] / len, n_in[1] / len, n_in[2] / len};
    const std::array<double, 3> c{c_in[0], c_in[1], c_in[2]};
    std::array<std::array<double, 3>, 8> v;
    std::array<double, 8> s;
    for (int k = 0; k < 8; ++k) {
        v[k] = {(k & 1) ? hi[0] : lo[0], (k & 2) ? hi[1] : lo[1], (k & 4) ? hi[2] : lo[2]};
        s[k] = n[0] * (v[k][0] - c[0]) + n[1] * (v[k][1] - c[1]) + n[2] * (v[k][2] - c[2]);
    }
    std::vector<std::array<double, 3>> pts;
    for (int k = 0; k < 8; ++k)
        if (s[k] == 0) pts.push_back(v[k]);
    for (int a = 0; a < 8; ++a)
        for (int bit = 1; bit < 8; bit <<= 1) {
            const int b = a | bit;
            if (b == a) continue;  // edges a -> a + bit with that bit clear in a
            if ((s[a] < 0 && s[b] > 0) || (s[a] > 0 && s[b] < 0)) {
                const double t = s[a] / (s[a] - s[b]);
                pts.push_back({v[a][0] + t * (v[b][0] - v[a][0]), v[a][1] + t * (v[b][1] - v[a][1]),
                               v[a][2] + t * (v[b][2] - v[a][2])});
            }
        }
    if (pts.empty()) return std::numeric_limits<double>::infinity();
    // an orthonormal frame (u, w) of the plane
    std::array<double, 3> helper = std::fabs(n[0]) < 0.6   ? std::array<double, 3>{1, 0, 0}
                                   : std::fabs(n[1]) < 0.6 ? std::array<double, 3>{0, 1, 0}
                                                           : std::array<double, 3>{0, 0, 1};
    std::array<double, 3> u{n[1] * helper[2] - n[2] * helper[1], n[2] * helper[0] - n[0] * helper[2],
                            n[0] * helper[1] - n[1] * helper[0]};
    const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& x : u) x /= ul;
    const std::array<double, 3> w{n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2],
                                  n[0] * u[1] - n[1] * u[0]};
    std::vector<std::array<double, 2>> q;
    for (const auto& p : pts) {
        const double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
        q.push_back({d[0] * u[0] + d[1] * u[1] + d[2] * u[2], d[0] * w[0] + d[1] * w[1] + d[2] * w[2]});
    }
    double gx = 0, gy = 0;
    for (const auto& p : q) {
        gx += p[0];
        gy += p[1];
    }
    gx /= double(q.size());
    gy /= double(q.size());
    std::sort(q.begin(), q.end(), [&](const auto& a, const auto& b) {
        return std::atan2(a[1] - gy, a[0] - gx) < std::atan2(b[1] - gy, b[0] - gx);
    });
    // inside test (counter-clockwise convex polygon, origin = the disk centre)
    if (q.size() >= 3) {
        bool inside = true;
        for (std::size_t i = 0; i < q.size() && inside; ++i) {
            const auto& a = q[i];
            const auto& b = q[(i + 1) % q.size()];
            const double cross = (b[0] - a[0]) * (0 - a[1]) - (b[1] - a[1]) * (0 - a[0]);
            if (cross < 0) inside = false;
        }
        if (inside) return 0.0;
    }
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < q.size(); ++i) {
        const auto& a = q[i];
        const auto& b = q[(i + 1) % q.size()];
        const double ex = b[0] - a[0], ey = b[1] - a[1];
        const double e2 = ex * ex + ey * ey;
        double t = e2 > 0 ? -(a[0] * ex + a[1] * ey) / e2 : 0.0;
        t = std::clamp(t, 0.0, 1.0);
        const double px = a[0] + t * ex, py = a[1] + t * ey;
        best = std::min(best, std::sqrt(px * px + py * py));
    }
    return best;
}

/// Overlap per the reference, with a relative tolerance band: +1 overlaps clearly, -1 clearly not,
/// 0 too close to the boundary (|distance - r| within tol * r) to call.
inline int reference_disk_box_overlap(const double c[3], const double n[3], double r, const double lo[3],
                                      const double hi[3], double tol = 1e-6) {
    const double d = reference_plane_box_distance(c, n, lo, hi);
    if (!std::isfinite(d)) {
        // the plane misses the box, but a box touching the plane within rounding is "too close"
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        double smin = 0, smax = 0;
        for (int a = 0; a < 3; ++a) {
            const double x = n[a] / len * (lo[a] - c[a]), y = n[a] / len * (hi[a] - c[a]);
            smin += std::min(x, y);
            smax += std::max(x, y);
        }
        const double gap = smin > 0 ? smin : -smax;
        return gap <= tol * r ? 0 : -1;
    }
    if (d < r * (1 - tol)) return 1;
    if (d > r * (1 + tol)) return -1;
    return 0;
}

}  // namespace prt::test
