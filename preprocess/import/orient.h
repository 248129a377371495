// PointRT prt-import: consistent orientation of estimated (sign-less) normals.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "prt/formats/pool_layout.h"

namespace prt::pre::import {

/// Sentinel in KnnGraph::neighbours where a point has fewer than k neighbours.
inline constexpr std::uint32_t k_no_neighbour = 0xFFFFFFFFu;

/// The k nearest other points of every point: neighbours[i * k + j], nearest first.
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
};

/// Hoppe et al. 1992, sec. 3.3 ("consistent tangent plane orientation"): propagate the sign along a
/// maximum spanning tree of the symmetric k-NN graph weighted by |n_i . n_j| (Hoppe's minimum
/// spanning tree on 1 - |n_i . n_j|), so the sign travels between nearly parallel planes first.
/// Each connected component gets its own seed: its point with the largest z, whose normal is
/// oriented to +z (outward: at the topmost point of a closed surface the outward normal is +z).
/// Prim's algorithm visits a point through the best edge from any already visited neighbour, so a
/// point is counted ambiguous when |n_i . n_j| < k_ambiguous_dot for EVERY neighbour j visited
/// before it; a seed is ambiguous when |n_z| < k_ambiguous_dot. Points with a non-finite or zero
/// normal take no part. Flips normals in place.
OrientStats orient_by_propagation(const std::vector<std::array<double, 3>>& positions,
                                  std::vector<pool::Float3>& normals, const KnnGraph& graph, bool quiet);

/// Flips every normal to face `sensor` (n . (sensor - p) >= 0). A point is ambiguous when its
/// normal is more than acos(k_ambiguous_dot) ~ 84 degrees from the line of sight (grazing view).
OrientStats orient_toward(const std::vector<std::array<double, 3>>& positions,
                          std::vector<pool::Float3>& normals, const std::array<double, 3>& sensor);

}  // namespace prt::pre::import
