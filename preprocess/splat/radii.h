// PointRT preprocess: splat radii from the k nearest neighbours (thesis 3.1), shared by prt-radii and
// the tests (library target prt_splat_radii).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "prt/formats/pool_layout.h"
#include "spill_file.h"
#include "tiled_knn.h"

namespace prt::pre {

/// What a radius is compared with before it is clamped (RadiiParams::clamp_factor).
enum class ClampScope : std::uint32_t {
    /// The median raw radius of the point's own k neighbours (issue 15): an isolated point among
    /// dense ones is clamped, a sparse region (far from the scanner, grazing, decimated) is not.
    local,
    /// The median radius of the whole model (the rule before issue 15): on scans whose density
    /// varies by more than the factor it clamps whole regions and leaves holes between them.
    global,
};
/// "local", "global"; parse throws prt::Error on another name.
const char* clamp_scope_name(ClampScope s);
ClampScope parse_clamp_scope(const std::string& name);

struct RadiiParams {
    std::uint32_t k = 9;        ///< thesis 3.1: radius = distance to the k-th nearest neighbour
    float clamp_factor = 3.0f;  ///< radii above clamp_factor x the scope's median are clamped to it; 0 = off
    ClampScope scope = ClampScope::local;
    unsigned threads = 0;  ///< worker threads; 0 = every hardware thread
    /// compute_radii()'s search: "cpu" (the kd-tree over `threads` workers) or "cuda" (device 0,
    /// runtime/cuda/src/knn.cu: the same radii bit for bit); resolve_radii_backend() turns "auto"
    /// into one of them.
    std::string backend = "cpu";
};

struct RadiiStats {
    std::uint64_t points = 0;
    std::uint64_t clamped = 0;  ///< radii lowered to the clamp limit
    std::uint64_t zero = 0;     ///< radii equal to 0 (k or more coincident neighbours): prt-octree skips them
    double raw_median = 0;      ///< median k-NN distance before clamping
    double clamp_limit = 0;     ///< global scope: clamp_factor x raw_median (0 otherwise)
    double min = 0, median = 0, mean = 0, max = 0;              ///< of the final radii
    double seconds_index = 0, seconds_search = 0, seconds = 0;  ///< cuda: the index includes the upload
    std::string backend = "cpu";                                ///< the search that ran: "cpu" or "cuda"
};

/// Whether the GPU search pays for n points against `threads` CPU workers (0 = every hardware
/// thread): from 100k points per thread. Below, the CPU is as fast as the GPU once its context is
/// made (about 0.2 s; H200 host, 1M points on 16 threads: 0.23 s CPU, 0.28 s CUDA in all).
bool radii_gpu_pays(std::uint64_t n, unsigned threads);

/// "cpu", or "cuda" when `name` is "cuda", or "auto" with radii_gpu_pays(n, threads), and device 0
/// can search n points with k neighbours (prt/cuda/knn_cuda.h knn_radii_usable: a device, k <= 32,
/// enough free memory). "auto" falls back to "cpu" with the reason in `why`; "cuda" throws
/// prt::Error with it.
std::string resolve_radii_backend(const std::string& name, std::uint64_t n, std::uint32_t k, unsigned threads,
                                  std::string* why = nullptr);

/// How a tool computes the radii of n points within `memory` bytes of its own.
struct RadiiPlan {
    std::string backend;  ///< "cpu" or "cuda"
    bool tiled = false;   ///< the CPU search out of core (compute_radii_tiled)
};

/// params.backend resolved as resolve_radii_backend() does, except that "auto" keeps the CPU when
/// the radii alone (4 bytes per point, what the CUDA search holds here) exceed `memory` or when
/// `force_tiles` (tests of the tiled search); the CPU search runs tiled when forced or when
/// radii_in_core_bytes() exceeds `memory`. `why`: why "auto" took the CPU.
RadiiPlan plan_radii(std::uint64_t n, const RadiiParams& params, std::uint64_t memory, bool force_tiles,
                     std::string* why = nullptr);

/// Distance from every point to its k-th nearest other point (exact k-NN through the shared kd-tree,
/// kd_tree.h, searched from `threads` threads). Coincident points count as neighbours at
/// distance 0. Throws prt::Error when there are not more than k points. `progress`, if set, is
/// called from one thread with the number of points done. With `neighbours`, also the indices
/// of each point's k nearest other points (neighbours[i * k + j], nearest first, ties by index).
std::vector<float> knn_distances(std::span<const pool::Float3> positions, std::uint32_t k, unsigned threads,
                                 const std::function<void(std::uint64_t)>& progress = {},
                                 RadiiStats* stats = nullptr,
                                 std::vector<std::uint32_t>* neighbours = nullptr);

/// The documented outlier rule: with m the median of `radii` and F = clamp_factor > 0, every radius
/// above F * m becomes F * m (isolated points otherwise get disks spanning the model). Fills the
/// clamp fields and the statistics of the result in `stats` (summed on `threads` workers, 0: every
/// core; the same bits for any count).
void clamp_radii(std::vector<float>& radii, float clamp_factor, RadiiStats& stats, unsigned threads = 1);

/// The local rule (issue 15): with m_i the median raw radius of point i's k neighbours
/// (`neighbours` as knn_distances gives them) and F = clamp_factor > 0, a radius above F * m_i
/// becomes F * m_i. Fills the statistics of the result in `stats`.
void clamp_radii_local(std::vector<float>& radii, const std::vector<std::uint32_t>& neighbours,
                       std::uint32_t k, float clamp_factor, RadiiStats& stats, unsigned threads = 0);

/// knn_distances() then the clamp of params.scope, on the CPU; with params.backend "cuda" the same
/// on device 0 (every radius and statistic equal; knn_cuda.h).
std::vector<float> compute_radii(std::span<const pool::Float3> positions, const RadiiParams& params,
                                 RadiiStats* stats = nullptr,
                                 const std::function<void(std::uint64_t)>& progress = {});

/// Bytes compute_radii() holds for n points (the kd-tree, the radii, the neighbour lists of the
/// local clamp and the clamped copy), for choosing between it and compute_radii_tiled().
std::uint64_t radii_in_core_bytes(std::uint64_t n, const RadiiParams& params);

/// compute_radii() out of core (issue 17): the k-NN tile by tile with a halo (tiled_knn.h, within
/// tiling.memory; tiling.k and tiling.threads are taken from `params`), the raw radii and the
/// neighbour lists of the local clamp in spill files in tiling.spill_folder, the clamp and the
/// statistics (exact medians by radix selection) streamed over them. Returns the radii in a spill
/// file, equal bit for bit to what compute_radii() returns, statistics included.
SpillFile compute_radii_tiled(std::span<const pool::Float3> positions, const RadiiParams& params,
                              TiledKnnParams tiling, RadiiStats* stats = nullptr,
                              TiledKnnStats* tiling_stats = nullptr,
                              const std::function<void(std::uint64_t)>& progress = {});

/// The median of `values` as clamp_radii() takes it (the middle element; the mean of the two
/// middle ones for an even count), by radix selection in four passes and O(1) memory. `mapped`:
/// `values` is a file mapping (a spill file) whose pages are dropped as the passes go (never set
/// it for memory of the heap: dropping would zero it).
double median_streaming(std::span<const float> values, bool mapped = false);

}  // namespace prt::pre
