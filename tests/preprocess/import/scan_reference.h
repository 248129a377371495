// Independent references for the real-scan tests and prt-bench-scans: the Stanford bunny's zippered
// mesh read by a plain parser here (not prt-import's readers), its area-weighted vertex normals,
// nearest-vertex queries over a uniform grid (not prt-import's kd-tree), and synthetic outliers.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "prt/formats/pool_layout.h"

namespace prt_scan_ref {

using Vec3 = std::array<double, 3>;

/// A triangle mesh from an ASCII PLY (vertex x y z first, then any scalar properties; faces as
/// "n i j k ..." fans), with area-weighted vertex normals (sum of the faces' cross products).
struct RefMesh {
    std::vector<Vec3> vertices;
    std::vector<Vec3> normals;  ///< unit, or zero for vertices on no face
    std::vector<std::array<std::uint32_t, 3>> triangles;
};

inline RefMesh read_ascii_ply_mesh(const std::string& path) {
    RefMesh m;
    std::ifstream in(path);
    std::string line;
    std::size_t vertices = 0, faces = 0, vertex_props = 0;
    bool in_vertex = false;
    while (std::getline(in, line) && line.rfind("end_header", 0) != 0) {
        std::istringstream w(line);
        std::string kw, name;
        w >> kw;
        if (kw == "element") {
            std::size_t c = 0;
            w >> name >> c;
            in_vertex = name == "vertex";
            (in_vertex ? vertices : faces) = c;
        } else if (kw == "property" && in_vertex) {
            ++vertex_props;
        }
    }
    m.vertices.resize(vertices);
    for (std::size_t i = 0; i < vertices && std::getline(in, line); ++i) {
        std::istringstream w(line);
        w >> m.vertices[i][0] >> m.vertices[i][1] >> m.vertices[i][2];
    }
    m.normals.assign(vertices, {0, 0, 0});
    for (std::size_t f = 0; f < faces && std::getline(in, line); ++f) {
        std::istringstream w(line);
        std::size_t n = 0;
        w >> n;
        std::vector<std::uint32_t> idx(n);
        for (auto& v : idx) w >> v;
        for (std::size_t t = 1; t + 1 < n; ++t) m.triangles.push_back({idx[0], idx[t], idx[t + 1]});
    }
    for (const auto& t : m.triangles) {
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const Vec3 cr{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        for (const std::uint32_t i : t)
            for (int k = 0; k < 3; ++k) m.normals[i][k] += cr[k];
    }
    for (auto& n : m.normals) {
        const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (l > 0)
            for (double& c : n) c /= l;
    }
    return m;
}

/// Nearest point of a fixed set by a uniform grid (cells of about `per_cell` points), searched in
/// growing shells of cells until no closer point can exist.
class GridNearest {
public:
    explicit GridNearest(const std::vector<Vec3>& points, double per_cell = 2.0) : m_points(points) {
        for (int a = 0; a < 3; ++a) {
            m_lo[a] = std::numeric_limits<double>::max();
            double hi = -m_lo[a];
            for (const auto& p : points) {
                m_lo[a] = std::min(m_lo[a], p[a]);
                hi = std::max(hi, p[a]);
            }
            m_extent[a] = std::max(hi - m_lo[a], 1e-12);
        }
        // A flat set (a plane) must not make the cells tiny: every extent at least 1e-3 of the largest.
        const double largest = std::max({m_extent[0], m_extent[1], m_extent[2]});
        for (double& e : m_extent) e = std::max(e, 1e-3 * largest);
        const double volume = m_extent[0] * m_extent[1] * m_extent[2];
        m_cell = std::cbrt(volume * per_cell / static_cast<double>(std::max<std::size_t>(points.size(), 1)));
        for (int a = 0; a < 3; ++a) m_dim[a] = std::max(1, static_cast<int>(m_extent[a] / m_cell) + 1);
        std::vector<std::uint32_t> count(static_cast<std::size_t>(m_dim[0]) * m_dim[1] * m_dim[2] + 1, 0);
        for (const auto& p : points) ++count[cell_of(p) + 1];
        for (std::size_t i = 1; i < count.size(); ++i) count[i] += count[i - 1];
        m_begin = count;
        m_index.resize(points.size());
        for (std::size_t i = 0; i < points.size(); ++i)
            m_index[count[cell_of(points[i])]++] = static_cast<std::uint32_t>(i);
    }

    /// Index of the nearest point to q and its distance; when none lies within `limit`, possibly
    /// {k_none, limit} (the search stops there).
    static constexpr std::uint32_t k_none = 0xFFFFFFFFu;
    std::pair<std::uint32_t, double> nearest(const Vec3& q,
                                             double limit = std::numeric_limits<double>::infinity()) const {
        int c[3];
        for (int a = 0; a < 3; ++a)
            c[a] = std::clamp(static_cast<int>((q[a] - m_lo[a]) / m_cell), 0, m_dim[a] - 1);
        double best = std::numeric_limits<double>::max();
        std::uint32_t best_i = k_none;
        for (int r = 0;; ++r) {
            // Cells at Chebyshev distance r from c; any point in them is at least (r - 1) cells away.
            if (r > 0 && (r - 1) * m_cell > std::sqrt(best)) break;
            if (r > 0 && (r - 1) * m_cell > limit) return {k_none, limit};
            if (r > m_dim[0] + m_dim[1] + m_dim[2]) break;
            for (int x = c[0] - r; x <= c[0] + r; ++x)
                for (int y = c[1] - r; y <= c[1] + r; ++y)
                    for (int z = c[2] - r; z <= c[2] + r; ++z) {
                        if (std::max({std::abs(x - c[0]), std::abs(y - c[1]), std::abs(z - c[2])}) != r)
                            continue;
                        if (x < 0 || y < 0 || z < 0 || x >= m_dim[0] || y >= m_dim[1] || z >= m_dim[2])
                            continue;
                        const std::size_t cell = (static_cast<std::size_t>(z) * m_dim[1] + y) * m_dim[0] + x;
                        for (std::uint32_t k = m_begin[cell]; k < m_begin[cell + 1]; ++k) {
                            const Vec3& p = m_points[m_index[k]];
                            const double d = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                             (p[2] - q[2]) * (p[2] - q[2]);
                            if (d < best) {
                                best = d;
                                best_i = m_index[k];
                            }
                        }
                    }
        }
        return {best_i, std::sqrt(best)};
    }

private:
    std::size_t cell_of(const Vec3& p) const {
        int c[3];
        for (int a = 0; a < 3; ++a)
            c[a] = std::clamp(static_cast<int>((p[a] - m_lo[a]) / m_cell), 0, m_dim[a] - 1);
        return (static_cast<std::size_t>(c[2]) * m_dim[1] + c[1]) * m_dim[0] + c[0];
    }
    const std::vector<Vec3>& m_points;
    double m_lo[3], m_extent[3], m_cell = 1;
    int m_dim[3];
    std::vector<std::uint32_t> m_begin, m_index;
};

/// Synthetic scanner outliers: `fraction` of the points (chosen at random) moved along their line
/// of sight by 5 to 25 % of `size`, away from or toward the sensor at random. `sensor` is a point
/// (kind 0) or a direction toward a far sensor (kind 1). Returns a per-point flag: 1 = moved.
inline std::vector<std::uint8_t> displace_outliers(std::vector<Vec3>& points, const prt::pool::Sensor& sensor,
                                                   double size, double fraction, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<std::uint8_t> moved(points.size(), 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (u(rng) >= fraction) continue;
        Vec3 d;
        for (int a = 0; a < 3; ++a)
            d[a] = sensor.kind == prt::pool::k_sensor_direction ? sensor.position[a]
                                                                : points[i][a] - sensor.position[a];
        const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double shift = (0.05 + 0.20 * u(rng)) * size * (u(rng) < 0.5 ? -1.0 : 1.0);
        for (int a = 0; a < 3; ++a) points[i][a] += d[a] / l * shift;
        moved[i] = 1;
    }
    return moved;
}

/// Distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
inline double point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    auto sub = [](const Vec3& x, const Vec3& y) { return Vec3{x[0] - y[0], x[1] - y[1], x[2] - y[2]}; };
    auto dot = [](const Vec3& x, const Vec3& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
    auto at = [&](double v, double w) {
        return Vec3{a[0] + v * (b[0] - a[0]) + w * (c[0] - a[0]),
                    a[1] + v * (b[1] - a[1]) + w * (c[1] - a[1]),
                    a[2] + v * (b[2] - a[2]) + w * (c[2] - a[2])};
    };
    const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
    Vec3 q;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    const Vec3 bp = sub(p, b);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    const Vec3 cp = sub(p, c);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0 && d2 <= 0)
        q = a;
    else if (d3 >= 0 && d4 <= d3)
        q = b;
    else if (vc <= 0 && d1 >= 0 && d3 <= 0)
        q = at(d1 / (d1 - d3), 0);
    else if (d6 >= 0 && d5 <= d6)
        q = c;
    else if (vb <= 0 && d2 >= 0 && d6 <= 0)
        q = at(0, d2 / (d2 - d6));
    else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        q = Vec3{b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])};
    } else {
        const double denom = 1 / (va + vb + vc);
        q = at(vb * denom, vc * denom);
    }
    const Vec3 d = sub(p, q);
    return std::sqrt(dot(d, d));
}

/// The diagonal of the bounding box.
inline double diagonal(const std::vector<Vec3>& points) {
    Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const auto& p : points)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

}  // namespace prt_scan_ref
