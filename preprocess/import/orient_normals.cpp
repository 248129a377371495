#include <algorithm>
#include <cmath>
#include <numeric>

#include "orient.h"
#include "orient_propagate.h"

namespace prt::pre::import {

using orient_detail::valid;

OrientStats orient_by_propagation(const std::vector<std::array<double, 3>>& positions,
                                  std::vector<pool::Float3>& normals, const KnnGraph& graph, bool quiet,
                                  const std::vector<std::uint8_t>* fixed,
                                  std::vector<std::uint32_t>* component) {
    OrientStats stats;
    const std::size_t n = normals.size();
    const std::uint32_t k = graph.k;
    std::vector<std::uint8_t> ok(n);
    for (std::size_t i = 0; i < n; ++i) {
        ok[i] = valid(normals[i]);
        if (!ok[i]) ++stats.skipped;
    }

    // Symmetric adjacency (CSR): k-NN is not symmetric, and a point must be reachable from every
    // point that lists it as a neighbour or the graph splits into needless components.
    std::vector<std::uint64_t> begin(n + 1, 0);
    auto each_edge = [&](auto&& fn) {
        for (std::size_t i = 0; i < n; ++i) {
            if (!ok[i]) continue;
            for (std::uint32_t j = 0; j < k; ++j) {
                const std::uint32_t m = graph.neighbours[i * k + j];
                if (m == k_no_neighbour || m == i || m >= n || !ok[m]) continue;
                fn(static_cast<std::uint32_t>(i), m);
            }
        }
    };
    each_edge([&](std::uint32_t a, std::uint32_t b) {
        ++begin[a + 1];
        ++begin[b + 1];
    });
    std::partial_sum(begin.begin(), begin.end(), begin.begin());
    std::vector<std::uint32_t> adjacent(begin[n]);
    {
        std::vector<std::uint64_t> fill(begin.begin(), begin.end() - 1);
        each_edge([&](std::uint32_t a, std::uint32_t b) {
            adjacent[fill[a]++] = b;
            adjacent[fill[b]++] = a;
        });
    }

    // A fixed point without a valid normal has no edges: passing `fixed` as it is changes nothing.
    return propagate_signs(
        n, begin, adjacent, normals, ok.data(), fixed ? fixed->data() : nullptr,
        [&](std::uint32_t v) { return positions[v][2]; }, quiet, component, stats);
}

OrientStats orient_toward(const std::vector<std::array<double, 3>>& positions,
                          std::vector<pool::Float3>& normals, const std::vector<pool::Sensor>& sensors,
                          const std::vector<std::uint16_t>& scan_ids, std::vector<std::uint8_t>* ambiguous,
                          const std::vector<std::uint8_t>* only) {
    OrientStats stats;
    if (ambiguous) ambiguous->assign(normals.size(), 0);
    for (std::size_t i = 0; i < normals.size(); ++i) {
        if (only && !(*only)[i]) continue;
        const int r =
            orient_toward_one(positions[i], normals[i], sensors[scan_ids.empty() ? 0 : scan_ids[i]]);
        if (r == 2) {
            ++stats.skipped;
        } else if (r == 1) {
            ++stats.ambiguous;
            if (ambiguous) (*ambiguous)[i] = 1;
        }
    }
    return stats;
}

OrientStats orient_toward(const std::vector<std::array<double, 3>>& positions,
                          std::vector<pool::Float3>& normals, const std::array<double, 3>& sensor) {
    const std::vector<pool::Sensor> sensors{
        pool::Sensor{{sensor[0], sensor[1], sensor[2]}, pool::k_sensor_point, 0}};
    return orient_toward(positions, normals, sensors, {});
}

}  // namespace prt::pre::import
