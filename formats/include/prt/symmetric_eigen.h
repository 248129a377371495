// PointRT: the eigen-decomposition of a symmetric 3x3 matrix (a covariance), shared by prt-import's
// normal estimation and the runtime's scan-frame fit. Host only.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "prt/vec3.h"

namespace prt {

/// Eigenvalues (ascending) and eigenvectors of a symmetric 3x3 matrix.
struct SymmetricEigen {
    Vec3d values;                  ///< ascending
    std::array<Vec3d, 3> vectors;  ///< vectors[i]: the eigenvector of values[i] (unit up to rounding)
};

/// Eigen-decomposition of the symmetric 3x3 matrix `a` (rows) by cyclic Jacobi rotations (Golub &
/// Van Loan, "Matrix Computations", 8.5): sweeps until the off-diagonal mass is below 1e-30 of the
/// diagonal's (at most 50).
inline SymmetricEigen symmetric_eigen(std::array<Vec3d, 3> a) {
    std::array<Vec3d, 3> v{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-30 * diag || off == 0.0) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t =
                    (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                for (int r = 0; r < 3; ++r) {  // A <- A J (columns p, q)
                    const double arp = a[r][p], arq = a[r][q];
                    a[r][p] = c * arp - s * arq;
                    a[r][q] = s * arp + c * arq;
                }
                for (int r = 0; r < 3; ++r) {  // A <- J^T A (rows p, q)
                    const double apr = a[p][r], aqr = a[q][r];
                    a[p][r] = c * apr - s * aqr;
                    a[q][r] = s * apr + c * aqr;
                }
                for (int r = 0; r < 3; ++r) {  // V <- V J
                    const double vrp = v[r][p], vrq = v[r][q];
                    v[r][p] = c * vrp - s * vrq;
                    v[r][q] = s * vrp + c * vrq;
                }
            }
    }
    std::array<int, 3> order{0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int x, int y) { return a[x][x] < a[y][y]; });
    SymmetricEigen e;
    for (int i = 0; i < 3; ++i) {
        e.values[i] = a[order[i]][order[i]];
        e.vectors[i] = {v[0][order[i]], v[1][order[i]], v[2][order[i]]};
    }
    return e;
}

}  // namespace prt
