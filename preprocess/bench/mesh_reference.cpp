#include "mesh_reference.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "prt/error.h"
#include "ray_reference.h"

namespace prt::bench {

namespace {

constexpr std::uint32_t k_leaf_triangles = 4;
constexpr double k_inf = std::numeric_limits<double>::infinity();

/// Entry t of the ray into the box, or +inf when it misses within [0, t_max].
double box_entry(const D3& lo, const D3& hi, const D3& o, const D3& inv_d, double t_max) {
    double t0 = 0, t1 = t_max;
    for (int a = 0; a < 3; ++a) {
        double ta = (lo[a] - o[a]) * inv_d[a], tb = (hi[a] - o[a]) * inv_d[a];
        if (ta > tb) std::swap(ta, tb);
        // NaN (0 * inf: the ray lies in a slab plane) keeps the interval: max/min ignore it
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
    }
    return t0 <= t1 ? t0 : k_inf;
}

double box_distance_sq(const D3& lo, const D3& hi, const D3& p) {
    double d = 0;
    for (int a = 0; a < 3; ++a) {
        const double e = p[a] < lo[a] ? lo[a] - p[a] : p[a] > hi[a] ? p[a] - hi[a] : 0.0;
        d += e * e;
    }
    return d;
}

/// Ericson 5.1.5: the point of triangle abc closest to p (Voronoi regions of the vertices and
/// edges, else the face).
D3 closest_on_triangle(const D3& p, const D3& a, const D3& b, const D3& c) {
    const D3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const D3 bp = sub(p, b);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return add(a, mul(ab, d1 / (d1 - d3)));
    const D3 cp = sub(p, c);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return add(a, mul(ac, d2 / (d2 - d6)));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return add(b, mul(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    const double denom = 1.0 / (va + vb + vc);
    return add(a, add(mul(ab, vb * denom), mul(ac, vc * denom)));
}

}  // namespace

MeshReference::MeshReference(std::vector<D3> vertices, std::vector<std::array<std::uint32_t, 3>> triangles)
    : m_vertices(std::move(vertices)) {
    // Drop degenerate and out-of-range triangles; orient by the signed volume.
    double volume = 0;
    for (const auto& t : triangles) {
        if (t[0] >= m_vertices.size() || t[1] >= m_vertices.size() || t[2] >= m_vertices.size()) continue;
        const D3 &a = m_vertices[t[0]], &b = m_vertices[t[1]], &c = m_vertices[t[2]];
        const D3 n = cross(sub(b, a), sub(c, a));
        if (!(dot(n, n) > 0) || !std::isfinite(dot(n, n))) continue;
        m_tris.push_back(t);
        volume += dot(a, cross(b, c));
    }
    if (m_tris.empty()) throw Error("reference mesh: no usable triangle");
    if (volume < 0) {
        m_flipped = true;
        for (auto& t : m_tris) std::swap(t[1], t[2]);
    }
    // Area-weighted vertex normals (the sum of the unnormalised face normals around a vertex).
    m_vertex_normals.assign(m_vertices.size(), D3{0, 0, 0});
    for (const auto& t : m_tris) {
        const D3 n = cross(sub(m_vertices[t[1]], m_vertices[t[0]]), sub(m_vertices[t[2]], m_vertices[t[0]]));
        for (int k = 0; k < 3; ++k) m_vertex_normals[t[k]] = add(m_vertex_normals[t[k]], n);
    }
    for (D3& n : m_vertex_normals) {
        const double l = std::sqrt(dot(n, n));
        if (l > 0) n = mul(n, 1.0 / l);
    }

    // Median-split BVH over the triangle centroids (longest axis of the centroid box).
    std::vector<D3> centroid(m_tris.size());
    for (std::size_t i = 0; i < m_tris.size(); ++i)
        centroid[i] =
            mul(add(add(m_vertices[m_tris[i][0]], m_vertices[m_tris[i][1]]), m_vertices[m_tris[i][2]]),
                1.0 / 3.0);
    std::vector<std::uint32_t> order(m_tris.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    m_nodes.push_back(Node{{}, {}, 0, std::uint32_t(order.size())});
    std::vector<std::uint32_t> work{0};
    while (!work.empty()) {
        const std::uint32_t ni = work.back();
        work.pop_back();
        const std::uint32_t first = m_nodes[ni].first, count = m_nodes[ni].count;
        D3 lo{k_inf, k_inf, k_inf}, hi{-k_inf, -k_inf, -k_inf}, clo = lo, chi = hi;
        for (std::uint32_t i = first; i < first + count; ++i) {
            for (int k = 0; k < 3; ++k) {
                const D3& v = m_vertices[m_tris[order[i]][k]];
                for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
            }
            for (int a = 0; a < 3; ++a)
                clo[a] = std::min(clo[a], centroid[order[i]][a]),
                chi[a] = std::max(chi[a], centroid[order[i]][a]);
        }
        m_nodes[ni].lo = lo;
        m_nodes[ni].hi = hi;
        if (count <= k_leaf_triangles) continue;
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
        const std::uint32_t mid = first + count / 2;
        std::nth_element(
            order.begin() + first, order.begin() + mid, order.begin() + first + count,
            [&](std::uint32_t a, std::uint32_t b) { return centroid[a][axis] < centroid[b][axis]; });
        const std::uint32_t left = std::uint32_t(m_nodes.size());
        m_nodes.push_back(Node{{}, {}, first, mid - first});
        m_nodes.push_back(Node{{}, {}, mid, first + count - mid});
        m_nodes[ni].first = left;
        m_nodes[ni].count = 0;
        work.push_back(left);
        work.push_back(left + 1);
    }
    // Leaves index `order`: store the triangles in that order.
    std::vector<std::array<std::uint32_t, 3>> sorted(m_tris.size());
    for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = m_tris[order[i]];
    m_tris = std::move(sorted);
    m_lo = m_nodes[0].lo;
    m_hi = m_nodes[0].hi;
}

bool MeshReference::intersect(const D3& o, const D3& d, double t_max, MeshHit& hit) const {
    const D3 inv{1.0 / d[0], 1.0 / d[1], 1.0 / d[2]};
    double best = t_max;
    std::uint32_t best_tri = 0;
    double best_u = 0, best_v = 0;
    bool found = false;
    std::uint32_t stack[128];
    int top = 0;
    if (box_entry(m_nodes[0].lo, m_nodes[0].hi, o, inv, best) == k_inf) return false;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = m_nodes[stack[--top]];
        if (box_entry(n.lo, n.hi, o, inv, best) == k_inf) continue;
        if (n.count > 0) {
            for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
                // Moller-Trumbore, two-sided
                const auto& t = m_tris[i];
                double th = 0, u = 0, v = 0;
                if (!ray_triangle(o, d, m_vertices[t[0]], m_vertices[t[1]], m_vertices[t[2]], 0, th, u, v))
                    continue;
                if (th > 0 && th < best) best = th, best_tri = i, best_u = u, best_v = v, found = true;
            }
            continue;
        }
        const Node &l = m_nodes[n.first], &r = m_nodes[n.first + 1];
        const double tl = box_entry(l.lo, l.hi, o, inv, best), tr = box_entry(r.lo, r.hi, o, inv, best);
        // nearer child searched first (pushed last)
        if (tl <= tr) {
            if (tr != k_inf) stack[top++] = n.first + 1;
            if (tl != k_inf) stack[top++] = n.first;
        } else {
            if (tl != k_inf) stack[top++] = n.first;
            if (tr != k_inf) stack[top++] = n.first + 1;
        }
    }
    if (!found) return false;
    const auto& t = m_tris[best_tri];
    const D3 &a = m_vertices[t[0]], &b = m_vertices[t[1]], &c = m_vertices[t[2]];
    hit.t = best;
    hit.point = add(o, mul(d, best));
    const D3 face = cross(sub(b, a), sub(c, a));
    hit.front = dot(face, d) < 0;
    const double w = 1 - best_u - best_v;
    D3 n = add(add(mul(m_vertex_normals[t[0]], w), mul(m_vertex_normals[t[1]], best_u)),
               mul(m_vertex_normals[t[2]], best_v));
    double l = std::sqrt(dot(n, n));
    if (!(l > 0)) n = face, l = std::sqrt(dot(face, face));
    hit.normal = mul(n, 1.0 / l);
    return true;
}

double MeshReference::distance(const D3& p) const {
    double best = k_inf;
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = m_nodes[stack[--top]];
        if (box_distance_sq(n.lo, n.hi, p) >= best) continue;
        if (n.count > 0) {
            for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
                const auto& t = m_tris[i];
                const D3 q = closest_on_triangle(p, m_vertices[t[0]], m_vertices[t[1]], m_vertices[t[2]]);
                const D3 e = sub(q, p);
                best = std::min(best, dot(e, e));
            }
            continue;
        }
        const Node &l = m_nodes[n.first], &r = m_nodes[n.first + 1];
        const double dl = box_distance_sq(l.lo, l.hi, p), dr = box_distance_sq(r.lo, r.hi, p);
        if (dl <= dr) {
            stack[top++] = n.first + 1;
            stack[top++] = n.first;
        } else {
            stack[top++] = n.first;
            stack[top++] = n.first + 1;
        }
    }
    return std::sqrt(best);
}

}  // namespace prt::bench
