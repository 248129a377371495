// Test-only data for the splat tests: analytic point sets and a brute-force O(n^2) k-NN in double.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "prt/formats/pool_layout.h"

namespace prt::test {

struct SplatSet {
    std::vector<pool::Float3> positions, normals;
    std::vector<float> radii;
};

/// n points uniformly at random on a sphere of radius `radius` around `centre`, radial normals.
inline SplatSet sphere_points(std::size_t n, std::uint64_t seed, double radius = 1.0,
                              const double centre[3] = nullptr) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    SplatSet s;
    for (std::size_t i = 0; i < n; ++i) {
        double v[3] = {g(rng), g(rng), g(rng)};
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (len < 1e-9) continue;
        for (double& x : v) x /= len;
        const double o[3] = {centre ? centre[0] : 0.0, centre ? centre[1] : 0.0, centre ? centre[2] : 0.0};
        s.positions.push_back(
            {float(o[0] + radius * v[0]), float(o[1] + radius * v[1]), float(o[2] + radius * v[2])});
        s.normals.push_back({float(v[0]), float(v[1]), float(v[2])});
    }
    return s;
}

/// Distance from each point to its k-th nearest other point, by brute force in double.
inline std::vector<double> brute_force_knn(const std::vector<pool::Float3>& p, std::uint32_t k) {
    std::vector<double> out(p.size());
    std::vector<double> d;
    for (std::size_t i = 0; i < p.size(); ++i) {
        d.clear();
        for (std::size_t j = 0; j < p.size(); ++j) {
            if (j == i) continue;
            const double dx = double(p[i].x) - p[j].x, dy = double(p[i].y) - p[j].y,
                         dz = double(p[i].z) - p[j].z;
            d.push_back(dx * dx + dy * dy + dz * dz);
        }
        std::nth_element(d.begin(), d.begin() + (k - 1), d.end());
        out[i] = std::sqrt(d[k - 1]);
    }
    return out;
}

}  // namespace prt::test
