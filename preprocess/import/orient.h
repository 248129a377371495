// PointRT prt-import: consistent orientation of estimated (sign-less) normals.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "prt/formats/pool_layout.h"

namespace prt::pre::import {

/// Sentinel in KnnGraph::neighbours where a point has fewer than k neighbours.
inline constexpr std::uint32_t k_no_neighbour = 0xFFFFFFFFu;

/// The k nearest other points of every point: neighbours[i * k + j], nearest first (neighbours.h
/// builds it over our kd-tree, knn.h).
struct KnnGraph {
    std::uint32_t k = 0;
    std::vector<std::uint32_t> neighbours;
};

/// |n_i . n_j| below this means the two tangent planes are nearly perpendicular: the relative sign
/// carries no information (the point is "ambiguous").
inline constexpr float k_ambiguous_dot = 0.1f;

struct OrientStats {
    std::uint64_t components = 0;  ///< connected components of the symmetric k-NN graph (one seed each)
    std::uint64_t ambiguous = 0;   ///< points whose sign is a guess (see the functions)
    std::uint64_t skipped = 0;     ///< points without a valid normal (left as they are)
    std::uint64_t flipped = 0;     ///< propagation from fixed points: non-fixed normals it flipped
};

/// Hoppe et al. 1992, sec. 3.3 ("consistent tangent plane orientation"): propagate the sign along a
/// maximum spanning tree of the symmetric k-NN graph weighted by |n_i . n_j| (Hoppe's minimum
/// spanning tree on 1 - |n_i . n_j|), so the sign travels between nearly parallel planes first.
/// When `fixed` is given, the points with fixed[i] set keep their sign and are the sources: every
/// point they reach takes its sign from them along the tree (one multi-source Prim), and counts in
/// `flipped` when that changed its sign. Every component without a fixed point gets its own seed:
/// its point with the largest z, whose normal is oriented to +z (outward: at the topmost point of a
/// closed surface the outward normal is +z). Prim's algorithm visits a point through the best edge
/// from any already visited neighbour, so a point is counted ambiguous when |n_i . n_j| <
/// k_ambiguous_dot for EVERY neighbour j visited before it; a seed is ambiguous when |n_z| <
/// k_ambiguous_dot (fixed points are not counted). `components` counts the +z seeds. Points with a
/// non-finite or zero normal take no part. Flips normals in place.
/// `component`, when not null, receives per point the number of the +z seed whose tree reached it
/// (0 for points reached from fixed points, and for points without a valid normal).
OrientStats orient_by_propagation(const std::vector<std::array<double, 3>>& positions,
                                  std::vector<pool::Float3>& normals, const KnnGraph& graph, bool quiet,
                                  const std::vector<std::uint8_t>* fixed = nullptr,
                                  std::vector<std::uint32_t>* component = nullptr);

/// Flips every normal to face its point's sensor: sensors[scan_ids[i]] (sensors[0] when scan_ids
/// is empty); a point sensor s: n . (s - p) >= 0; a direction sensor d (toward a far scanner):
/// n . d >= 0. A point is ambiguous (a grazing view) when its normal is more than
/// acos(k_ambiguous_dot) ~ 84.3 degrees from the line of sight (within ~5.7 degrees of
/// perpendicular); `ambiguous`, when not null, receives a per-point flag. Only points with
/// only[i] set (when `only` is not null) are touched.
OrientStats orient_toward(const std::vector<std::array<double, 3>>& positions,
                          std::vector<pool::Float3>& normals, const std::vector<pool::Sensor>& sensors,
                          const std::vector<std::uint16_t>& scan_ids,
                          std::vector<std::uint8_t>* ambiguous = nullptr,
                          const std::vector<std::uint8_t>* only = nullptr);

/// orient_toward() for one point: flips `normal` to face `sensor` from `position`. Returns 0 when
/// the normal is valid and not ambiguous, 1 when ambiguous (grazing), 2 when not valid (untouched).
inline int orient_toward_one(const std::array<double, 3>& position, pool::Float3& normal,
                             const pool::Sensor& sensor) {
    const float l = normal.x * normal.x + normal.y * normal.y + normal.z * normal.z;
    if (!(std::isfinite(l) && l > 1e-12f)) return 2;
    double d[3];
    for (int a = 0; a < 3; ++a)
        d[a] =
            sensor.kind == pool::k_sensor_direction ? sensor.position[a] : sensor.position[a] - position[a];
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double c = normal.x * d[0] + normal.y * d[1] + normal.z * d[2];
    if (c < 0.0) normal = {-normal.x, -normal.y, -normal.z};
    return !(len > 0.0) || std::fabs(c) < k_ambiguous_dot * len ? 1 : 0;
}

/// orient_toward() with one point sensor.
OrientStats orient_toward(const std::vector<std::array<double, 3>>& positions,
                          std::vector<pool::Float3>& normals, const std::array<double, 3>& sensor);

}  // namespace prt::pre::import
