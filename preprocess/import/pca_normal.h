// PointRT prt-import: the PCA normal of one point (Hoppe et al. 1992, sec. 3.2), shared by
// pca_normals() (in core, over a KnnGraph) and pca_normals_tiled() (out of core, issue 17) so both
// compute every normal with the same arithmetic.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "orient.h"
#include "prt/formats/pool_layout.h"
#include "prt/symmetric_eigen.h"

namespace prt::pre::import {

/// The least-squares plane normal of `self` and its neighbours row[0 .. others) (stopping at
/// k_no_neighbour), `position(j)` giving neighbour j's position: the eigenvector of their
/// covariance with the smallest eigenvalue (coordinates relative to the point, double). Leaves
/// `normal` as it is when there are fewer than 3 points or they are coincident or collinear.
template <class Position>
void pca_normal(const std::array<double, 3>& self, const std::uint32_t* row, std::uint32_t others,
                Position&& position, pool::Float3& normal) {
    // Coordinates relative to the point itself: double sums of small numbers.
    double d[257][3];
    std::uint32_t m = 0;
    d[m][0] = d[m][1] = d[m][2] = 0.0;
    ++m;
    for (std::uint32_t j = 0; j < others; ++j) {
        if (row[j] == k_no_neighbour) break;
        const std::array<double, 3>& q = position(row[j]);
        for (int a = 0; a < 3; ++a) d[m][a] = q[a] - self[a];
        ++m;
    }
    if (m < 3) return;
    double mean[3] = {0, 0, 0};
    for (std::uint32_t j = 0; j < m; ++j)
        for (int a = 0; a < 3; ++a) mean[a] += d[j][a];
    for (int a = 0; a < 3; ++a) mean[a] /= m;
    std::array<Vec3d, 3> c{};
    for (std::uint32_t j = 0; j < m; ++j) {
        const double x = d[j][0] - mean[0], y = d[j][1] - mean[1], z = d[j][2] - mean[2];
        c[0][0] += x * x;
        c[0][1] += x * y;
        c[0][2] += x * z;
        c[1][1] += y * y;
        c[1][2] += y * z;
        c[2][2] += z * z;
    }
    c[1][0] = c[0][1];
    c[2][0] = c[0][2];
    c[2][1] = c[1][2];
    const SymmetricEigen eigen = symmetric_eigen(c);
    const Vec3d& w = eigen.values;
    const Vec3d& v = eigen.vectors[0];
    if (!(w[2] > 0.0) || w[1] <= 1e-10 * w[2]) return;  // coincident or collinear
    const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(len > 0.0) || !std::isfinite(len)) return;
    normal = {static_cast<float>(v[0] / len), static_cast<float>(v[1] / len), static_cast<float>(v[2] / len)};
}

}  // namespace prt::pre::import
