#include <algorithm>
#include <cmath>
#include <random>

#include "mesh.h"
#include "prt/error.h"
#include "prt/vec3.h"

namespace prt::pre::import {

namespace {

using Vec = Vec3d;

inline pool::Float3 unit_or_zero(const Vec& v) {
    const double len = length(v);
    if (!(len > 0.0) || !std::isfinite(len)) return {0.f, 0.f, 0.f};
    return {static_cast<float>(v[0] / len), static_cast<float>(v[1] / len), static_cast<float>(v[2] / len)};
}

/// Uniform double in [0, 1) from the top 53 bits (the same numbers on every platform).
inline double uniform(std::mt19937_64& rng) {
    return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

}  // namespace

std::array<double, 3> face_area_vector(const MeshData& mesh, std::size_t f) {
    const std::uint32_t b = mesh.face_begin[f];
    const std::uint32_t e = mesh.face_begin[f + 1];
    Vec sum{0, 0, 0};
    if (e - b < 3) return sum;
    // Fan around the first vertex: sum_i (v_i - v_0) x (v_{i+1} - v_0) equals Newell's
    // sum_i v_i x v_{i+1}, but relative coordinates keep precision for models far from the origin.
    const Vec& v0 = mesh.vertices[mesh.face_indices[b]];
    for (std::uint32_t i = b + 1; i + 1 < e; ++i) {
        const Vec c = cross(sub(mesh.vertices[mesh.face_indices[i]], v0),
                            sub(mesh.vertices[mesh.face_indices[i + 1]], v0));
        sum[0] += c[0];
        sum[1] += c[1];
        sum[2] += c[2];
    }
    return sum;
}

std::vector<pool::Float3> area_weighted_normals(const MeshData& mesh) {
    // Area-weighted vertex normals: n_v = normalize(sum over faces f around v of area_f * n_f).
    // face_area_vector is 2 * area_f * n_f; the common factor 2 cancels in the normalisation.
    std::vector<Vec> sum(mesh.vertices.size(), Vec{0, 0, 0});
    std::vector<double> total(mesh.vertices.size(), 0.0);  // sum of |area vectors| around v
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
        const Vec a = face_area_vector(mesh, f);
        const double len = length(a);
        for (std::uint32_t i = mesh.face_begin[f]; i < mesh.face_begin[f + 1]; ++i) {
            const std::uint32_t v = mesh.face_indices[i];
            sum[v][0] += a[0];
            sum[v][1] += a[1];
            sum[v][2] += a[2];
            total[v] += len;
        }
    }
    std::vector<pool::Float3> normals(sum.size());
    for (std::size_t v = 0; v < sum.size(); ++v) {
        // Faces that cancel (a double-sided sheet: the same triangle with both windings) leave only
        // rounding noise, whose direction means nothing: no normal.
        normals[v] = length(sum[v]) > k_cancelled_normal * total[v] ? unit_or_zero(sum[v])
                                                                    : pool::Float3{0.f, 0.f, 0.f};
    }
    return normals;
}

PointCloud mesh_vertices(const MeshData& mesh, bool file_normals, Report& report) {
    PointCloud cloud;
    cloud.positions = mesh.vertices;
    std::vector<std::uint8_t> used(mesh.vertices.size(), 0);
    for (std::uint32_t idx : mesh.face_indices) used[idx] = 1;
    report.unreferenced_vertices =
        static_cast<std::uint64_t>(std::count(used.begin(), used.end(), std::uint8_t{0}));
    const bool have_file = mesh.vertex_normals.size() == mesh.vertices.size();
    auto is_zero = [](const pool::Float3& n) { return n.x == 0.f && n.y == 0.f && n.z == 0.f; };
    const std::vector<pool::Float3> weighted = area_weighted_normals(mesh);
    cloud.normals.resize(mesh.vertices.size());
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
        const pool::Float3 from_file = have_file ? mesh.vertex_normals[v] : pool::Float3{0.f, 0.f, 0.f};
        // Preferred source first, the other as the fallback where the preferred one has no normal.
        const pool::Float3& first = file_normals ? from_file : weighted[v];
        const pool::Float3& second = file_normals ? weighted[v] : from_file;
        if (!is_zero(first)) {
            cloud.normals[v] = first;
            (file_normals ? report.normals_from_file : report.normals_area_weighted) = true;
        } else {
            if (used[v] && is_zero(weighted[v])) ++report.cancelled_normals;
            cloud.normals[v] = second;
            if (!is_zero(second)) {
                ++report.fallback_normals;
                (file_normals ? report.normals_area_weighted : report.normals_from_file) = true;
            }
        }
    }
    if (mesh.vertex_colors.size() == mesh.vertices.size()) cloud.colors = mesh.vertex_colors;
    return cloud;
}

PointCloud sample_mesh(const MeshData& mesh, std::uint64_t count, std::uint64_t seed, SampleNormals mode) {
    // Fan triangles (first vertex, i, i+1) of every face with their areas as a cumulative table.
    struct Tri {
        std::uint32_t a, b, c;
    };
    std::vector<Tri> tris;
    std::vector<double> cdf;
    tris.reserve(mesh.face_indices.size());
    cdf.reserve(mesh.face_indices.size());
    double total = 0.0;
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
        const std::uint32_t b = mesh.face_begin[f];
        const std::uint32_t e = mesh.face_begin[f + 1];
        for (std::uint32_t i = b + 1; i + 1 < e; ++i) {
            const Tri t{mesh.face_indices[b], mesh.face_indices[i], mesh.face_indices[i + 1]};
            const double area = 0.5 * length(cross(sub(mesh.vertices[t.b], mesh.vertices[t.a]),
                                                   sub(mesh.vertices[t.c], mesh.vertices[t.a])));
            if (!(area > 0.0) || !std::isfinite(area)) continue;  // never chosen
            total += area;
            tris.push_back(t);
            cdf.push_back(total);
        }
    }
    if (tris.empty()) throw Error("the mesh has no face with a positive area: nothing to sample");

    const bool interpolated = mode == SampleNormals::interpolated;
    const std::vector<pool::Float3> vertex_normals =
        interpolated ? area_weighted_normals(mesh) : std::vector<pool::Float3>{};
    const bool colors = mesh.vertex_colors.size() == mesh.vertices.size();

    PointCloud cloud;
    cloud.positions.resize(count);
    cloud.normals.resize(count);
    if (colors) cloud.colors.resize(count);
    std::mt19937_64 rng(seed);
    for (std::uint64_t s = 0; s < count; ++s) {
        // A triangle with probability area / total, then a uniform point in it: with r1, r2
        // uniform, barycentrics (1 - sqrt(r1), sqrt(r1) (1 - r2), sqrt(r1) r2) are uniform by area
        // (Osada et al. 2002, "Shape distributions", sec. 4.2).
        const double pick = uniform(rng) * total;
        std::size_t t =
            static_cast<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin());
        t = std::min(t, tris.size() - 1);
        const Tri& tri = tris[t];
        const double r1 = std::sqrt(uniform(rng));
        const double r2 = uniform(rng);
        const double wa = 1.0 - r1, wb = r1 * (1.0 - r2), wc = r1 * r2;
        const Vec& A = mesh.vertices[tri.a];
        const Vec& B = mesh.vertices[tri.b];
        const Vec& C = mesh.vertices[tri.c];
        for (int k = 0; k < 3; ++k) cloud.positions[s][k] = wa * A[k] + wb * B[k] + wc * C[k];
        const pool::Float3 face = unit_or_zero(cross(sub(B, A), sub(C, A)));
        if (interpolated) {
            const pool::Float3 &na = vertex_normals[tri.a], &nb = vertex_normals[tri.b],
                               &nc = vertex_normals[tri.c];
            const pool::Float3 n =
                unit_or_zero({wa * na.x + wb * nb.x + wc * nc.x, wa * na.y + wb * nb.y + wc * nc.y,
                              wa * na.z + wb * nb.z + wc * nc.z});
            cloud.normals[s] = (n.x == 0.f && n.y == 0.f && n.z == 0.f) ? face : n;
        } else {
            cloud.normals[s] = face;
        }
        if (colors) {
            const pool::Rgba8 &ca = mesh.vertex_colors[tri.a], &cb = mesh.vertex_colors[tri.b],
                              &cc = mesh.vertex_colors[tri.c];
            auto mix = [&](std::uint8_t a, std::uint8_t b, std::uint8_t c) {
                return static_cast<std::uint8_t>(std::clamp(std::lround(wa * a + wb * b + wc * c), 0L, 255L));
            };
            cloud.colors[s] = {mix(ca.r, cb.r, cc.r), mix(ca.g, cb.g, cc.g), mix(ca.b, cb.b, cc.b),
                               mix(ca.a, cb.a, cc.a)};
        }
    }
    return cloud;
}

}  // namespace prt::pre::import
