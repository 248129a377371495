#include "point_spacing.h"

#include <cmath>

#include "prt/error.h"
#include "prt/parallel.h"

namespace prt::bench {

namespace {

const std::vector<P3>& checked(const std::vector<P3>& points) {
    if (points.size() < 2) throw Error("point index: need at least 2 points");
    if (points.size() >= 0xffffffffu) throw Error("point index: too many points");
    for (const P3& p : points)
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw Error("point index: a point is not finite");
    return points;
}

}  // namespace

PointIndex::PointIndex(std::vector<P3> points)
    : m_points(std::move(points)), m_tree(checked(m_points).size(), [this](std::size_t i, double c[3]) {
          for (int a = 0; a < 3; ++a) c[a] = m_points[i][a];
      }) {}

std::uint32_t PointIndex::nearest(const P3& q, double& distance) const {
    std::uint32_t index = 0;
    double d2 = 0;
    m_tree.search(q.data(), ~0u, 1, nullptr, &index, &d2);
    distance = std::sqrt(d2);
    return index;
}

void PointIndex::knn(const P3& q, std::uint32_t k, std::uint32_t skip, std::vector<double>& out) const {
    std::vector<std::uint32_t> index(k);
    out.resize(k);
    out.resize(m_tree.search(q.data(), skip, k, nullptr, index.data(), out.data()));
    for (double& d : out) d = std::sqrt(d);
}

void PointIndex::knn_indices(const P3& q, std::uint32_t k, std::vector<std::uint32_t>& out) const {
    std::vector<double> d2(k);
    out.resize(k);
    out.resize(m_tree.search(q.data(), ~0u, k, nullptr, out.data(), d2.data()));
}

std::vector<double> PointIndex::local_spacing(unsigned threads) const {
    std::vector<double> s(m_points.size());
    const double factor = std::sqrt(M_PI / double(k_spacing_neighbours));
    m_tree.for_each(k_spacing_neighbours, threads,
                    [&](std::uint32_t i, const std::uint32_t*, const double* d2, std::uint32_t found) {
                        s[i] = found == 0 ? 0.0 : std::sqrt(d2[found - 1]) * factor;
                    });
    return s;
}

}  // namespace prt::bench
