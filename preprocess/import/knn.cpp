#include "knn.h"

#include <algorithm>

namespace prt::pre::import {

namespace {

std::array<double, 3> box_centre(const std::vector<std::array<double, 3>>& positions) {
    if (positions.empty()) return {0, 0, 0};
    std::array<double, 3> lo = positions[0], hi = positions[0];
    for (const auto& p : positions)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    return {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
}

}  // namespace

KdTree::KdTree(const std::vector<std::array<double, 3>>& positions, unsigned threads)
    : pre::KdTree<float>(
          positions.size(),
          [&, centre = box_centre(positions)](std::size_t i, float c[3]) {
              for (int a = 0; a < 3; ++a) c[a] = static_cast<float>(positions[i][a] - centre[a]);
          },
          threads) {}

}  // namespace prt::pre::import
