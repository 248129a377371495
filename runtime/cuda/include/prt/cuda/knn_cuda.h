// PointRT CUDA: prt-radii's GPU path (thesis 3.1, issue 17): the exact k-nearest-neighbour radii
// of a point set, and their outlier clamp, on device 0. Plain C++ header (no CUDA types), so
// preprocess/splat/radii.cpp, compiled by g++, calls it. Implemented in runtime/cuda/src/knn.cu
// (target prt_knn_cuda, built only with nvcc, without FMA contraction and without fast math).
//
// The result equals the CPU path's (preprocess/splat/radii.h, common/kd_tree.h) bit for bit: the
// same squared distances in float (dx * dx + dy * dy + dz * dz, d = point - query, no fused
// multiply-add), the same order of candidates (squared distance, then the smaller index), the same
// clamp arithmetic, the same medians.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

namespace prt::cuda {

/// The largest k the GPU search keeps in registers.
inline constexpr std::uint32_t k_knn_max_k = 32;

/// The clamp after the search (radii.h ClampScope and RadiiParams::clamp_factor).
enum class KnnClamp : std::uint32_t {
    none,    ///< the raw radii
    global,  ///< radii above factor x the median raw radius become that value
    local,   ///< radii above factor x the median raw radius of their k neighbours become that value
};

/// How knn_radii_cuda()'s local clamp finds each point's neighbours again once every raw radius is
/// known (the same neighbours, the same radii either way).
enum class KnnNeighbours : std::uint32_t {
    stored_if_free,  ///< stored by the search (4k bytes a point) where the device has them free, else
                     ///< searched again
    searched_again,  ///< a second search (no memory beyond the search's; about as long as the first)
};

/// What knn_radii_cuda() found besides the radii.
struct KnnRadiiResult {
    /// The first point (index) with a non-finite coordinate, or -1. When set, nothing else is.
    std::int64_t non_finite = -1;
    double raw_median =
        0;  ///< the median raw radius (radii.cpp's median: the mean of the two middle ones for even n)
    double median = 0;      ///< the median final radius
    float clamp_limit = 0;  ///< global clamp: the limit (0 otherwise)
    std::uint64_t clamped = 0;
    double seconds_upload = 0, seconds_index = 0, seconds_search = 0, seconds_clamp = 0;
    bool neighbours_stored = false;  ///< the local clamp read the neighbours the search stored
};

/// Device bytes knn_radii_cuda() needs for n points (its peak: the Morton sort).
std::uint64_t knn_radii_device_bytes(std::uint64_t n);

/// Whether device 0 can run knn_radii_cuda() for n points and k neighbours now: a device, k <=
/// k_knn_max_k, n below 2^32 - 1, enough free device memory. On false, `why` gets one line. Never
/// throws.
bool knn_radii_usable(std::uint64_t n, std::uint32_t k, std::string* why = nullptr);

/// The distance from every point of `xyz` (x, y, z per point, host memory, 3n floats) to its k-th
/// nearest other point, clamped as `clamp` says with `factor` (> 0 for global and local), into
/// `radii` (n floats, host memory, index order). n > k. `progress(done)` (points, of n) is called
/// from the calling thread between launches. Throws prt::Error on a CUDA error.
KnnRadiiResult knn_radii_cuda(std::span<const float> xyz, std::uint32_t k, KnnClamp clamp, float factor,
                              std::span<float> radii, const std::function<void(std::uint64_t)>& progress = {},
                              KnnNeighbours neighbour_store = KnnNeighbours::stored_if_free);

}  // namespace prt::cuda
