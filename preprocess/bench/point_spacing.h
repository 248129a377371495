// PointRT fidelity measurement (issue 15): where a scan has data and how dense it is there.
//
// The exact kd-tree of the tools (preprocess/common/kd_tree.h) over the input points in double
// precision, world frame; it is tested against brute force (tests/preprocess/common), so the measure
// rests on an exact search, not on the radii the pipeline derived from it.
//
// Local spacing. On a surface sampled with density rho (points per unit area), the distance to the
// k-th nearest neighbour is about r_k = sqrt(k / (pi rho)); the spacing of a square grid of that
// density is 1 / sqrt(rho) = r_k sqrt(pi / k). The local spacing of point i is that estimate with
// k = 8 (k_spacing_neighbours): s_i = r_8(i) sqrt(pi / 8). It is the unit of every distance the
// fidelity tool reports, so a figure means the same on a 1 mm and on a 1 km scan.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "kd_tree.h"
#include "prt/vec3.h"

namespace prt::bench {

using P3 = Vec3d;

/// Neighbours used for the local spacing estimate.
inline constexpr std::uint32_t k_spacing_neighbours = 8;

class PointIndex {
public:
    /// Builds the tree over `points` (copied). Throws prt::Error when fewer than 2 points.
    explicit PointIndex(std::vector<P3> points);

    std::size_t size() const { return m_points.size(); }
    const P3& point(std::uint32_t i) const { return m_points[i]; }

    /// The nearest point to q: its index and distance.
    std::uint32_t nearest(const P3& q, double& distance) const;
    /// Distances to the k nearest points of q (ascending; fewer when the tree holds fewer),
    /// excluding index `skip` (use ~0u for none).
    void knn(const P3& q, std::uint32_t k, std::uint32_t skip, std::vector<double>& out) const;
    /// Indices of the k nearest points of q, nearest first.
    void knn_indices(const P3& q, std::uint32_t k, std::vector<std::uint32_t>& out) const;

    /// The local spacing s_i of every point (see the header), computed on `threads` threads.
    std::vector<double> local_spacing(unsigned threads) const;

private:
    std::vector<P3> m_points;
    pre::KdTree<double> m_tree;
};

}  // namespace prt::bench
