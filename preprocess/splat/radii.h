// PointRT preprocess: splat radii from the k nearest neighbours (thesis 3.1), shared by prt-radii and
// the tests. Needs FLANN (library target prt_splat_radii, built only when FLANN is found).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "prt/formats/pool_layout.h"

namespace prt::pre {

struct RadiiParams {
    std::uint32_t k = 9;        ///< thesis 3.1: radius = distance to the k-th nearest neighbour
    float clamp_factor = 3.0f;  ///< radii above clamp_factor x the median radius are clamped to it; 0 = off
    unsigned threads = 0;       ///< worker threads; 0 = every hardware thread
};

struct RadiiStats {
    std::uint64_t points = 0;
    std::uint64_t clamped = 0;  ///< radii lowered to the clamp limit
    std::uint64_t zero = 0;     ///< radii equal to 0 (k or more coincident neighbours): prt-octree skips them
    double raw_median = 0;      ///< median k-NN distance before clamping
    double clamp_limit = 0;     ///< clamp_factor x raw_median (0 when clamping is off)
    double min = 0, median = 0, mean = 0, max = 0;  ///< of the final radii
    double seconds_index = 0, seconds_search = 0, seconds = 0;
};

/// Distance from every point to its k-th nearest other point (exact k-NN through a FLANN
/// KDTreeSingleIndex, searched from `threads` threads). Coincident points count as neighbours at
/// distance 0. Throws prt::Error when there are not more than k points. `progress`, if set, is
/// called from one thread with the number of points done.
std::vector<float> knn_distances(std::span<const pool::Float3> positions, std::uint32_t k, unsigned threads,
                                 const std::function<void(std::uint64_t)>& progress = {},
                                 RadiiStats* stats = nullptr);

/// The documented outlier rule: with m the median of `radii` and F = clamp_factor > 0, every radius
/// above F * m becomes F * m (isolated points otherwise get disks spanning the model). Fills the
/// clamp fields and the statistics of the result in `stats`.
void clamp_radii(std::vector<float>& radii, float clamp_factor, RadiiStats& stats);

/// knn_distances() then clamp_radii().
std::vector<float> compute_radii(std::span<const pool::Float3> positions, const RadiiParams& params,
                                 RadiiStats* stats = nullptr,
                                 const std::function<void(std::uint64_t)>& progress = {});

}  // namespace prt::pre
