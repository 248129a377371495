// PointRT prt-import: what one k-NN pass over a scan serves: outlier removal (statistical and
// radius, PCL's StatisticalOutlierRemoval and RadiusOutlierRemoval semantics), the k-NN graph for
// PCA normals (Hoppe et al. 1992, sec. 3.2) and for orientation (orient.h). All over our own
// kd-tree (knn.h), so every build gives the same result.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "orient.h"
#include "point_cloud.h"
#include "tiled_knn.h"

namespace prt::pre::import {

/// --keep-outliers, --outlier-k, --outlier-std, --outlier-radius, --outlier-min-neighbours.
struct OutlierParams {
    bool enabled = true;
    /// Statistical: a point's mean distance to its k nearest neighbours (itself excluded; PCL
    /// setMeanK) is compared to the mean and standard deviation of that value over the scan.
    std::uint32_t k = 8;
    /// Statistical: outlier when its mean distance > mean + std_ratio x standard deviation (PCL
    /// setStddevMulThresh). 0 disables the statistical test.
    double std_ratio = 8.0;
    /// Radius: the radius is this multiple of the scan's median spacing (the median over its points
    /// of the mean distance to the k nearest neighbours): scale-free. 0 disables the radius test.
    double radius_factor = 3.0;
    /// Radius: outlier when fewer than this many other points lie within the radius (PCL
    /// setMinNeighborsInRadius; at most k, so the k-NN pass answers it).
    std::uint32_t min_neighbours = 2;
    /// The scan's scanner position when it is a point (set per scan by the import): a scanner's
    /// point spacing grows with range, so both tests then measure distances relative to the range,
    /// scaled to the scan's median range (issue 15: a room scanned from inside is dense near the
    /// scanner and sparse far away; without this the far walls set the statistics and floating
    /// points near the scanner pass).
    std::optional<std::array<double, 3>> sensor;
};

/// What outlier removal did on one scan.
struct OutlierReport {
    bool ran = false;
    std::string skipped;            ///< why it did not run (too few points, --keep-outliers), or ""
    std::uint64_t input = 0;        ///< points examined
    std::uint64_t removed = 0;      ///< points removed (flagged by either test)
    std::uint64_t statistical = 0;  ///< flagged by the statistical test
    std::uint64_t radius = 0;       ///< flagged by the radius test
    double mean = 0, stddev = 0;    ///< of the per-point mean k-NN distance
    double threshold = 0;           ///< statistical: mean + std_ratio x stddev
    double median_spacing = 0;      ///< median of the per-point mean k-NN distance
    double radius_used = 0;         ///< radius_factor x median_spacing
    bool range_scaled = false;      ///< distances were taken relative to the range (OutlierParams::sensor)
    double seconds = 0;
    std::string summary() const;  ///< one line
};

/// Whether outlier removal runs over `n` points: starts `report` (input count, and why it is
/// skipped when it is not). Throws prt::Error when it runs with --outlier-min-neighbours above
/// --outlier-k. Shared by outliers_and_graph() and the out-of-core import.
bool outlier_removal_runs(const OutlierParams& params, std::uint64_t n, OutlierReport& report);

/// One k-NN pass over `cloud` (kd-tree, knn.h) that removes the outliers of `params` from the
/// cloud (all its per-point attributes) and, when `graph_k` > 0, fills `graph` with the k-NN graph
/// of the points that remain (graph_k nearest other remaining points each, nearest first; a point
/// whose neighbours included a removed point is searched again without them). Counts in `report`.
/// With fewer than params.k + 1 points outlier removal is skipped (said in report.skipped).
void outliers_and_graph(PointCloud& cloud, const OutlierParams& params, std::uint32_t graph_k,
                        KnnGraph* graph, OutlierReport& report, bool quiet);

/// PCA normals from a k-NN graph (Hoppe et al. 1992, sec. 3.2; thesis 3.1): the least-squares
/// plane of the point and its k - 1 nearest neighbours (k points in all, PCL NormalEstimation's
/// setKSearch(k)); the normal is the eigenvector of their covariance with the smallest eigenvalue
/// (cyclic Jacobi, double precision, coordinates relative to the point). Unoriented. A point whose
/// neighbourhood has fewer than 3 points or is degenerate (coincident or collinear points: the two
/// smaller eigenvalues below 1e-10 of the largest) gets a NaN normal.
std::vector<pool::Float3> pca_normals(const std::vector<std::array<double, 3>>& positions,
                                      const KnnGraph& graph, std::uint32_t k, bool quiet);

/// pca_normals() out of core (issue 17): the k - 1 nearest neighbours PCA uses are searched tile
/// by tile with a halo (tiled_knn.h, within tiling.memory; tiling.k is set here) over the same
/// float offsets from the bounding-box centre as the in-core KdTree (knn.h), which go to a spill
/// file in tiling.spill_folder; each point's normal is computed (pca_normal.h) as soon as its
/// neighbours are final and written to `normals` (positions.size(); may be a spill file). Equal
/// bit for bit to pca_normals() over the graph outliers_and_graph() builds with no outlier removed.
/// `positions` may be a mapped file too (it is read in tile order). `centre`, when not null, is
/// the centre of the float frame instead of the positions' bounding-box centre: the in-core
/// KdTree's when outlier removal took points away after it was built (import out of core).
/// tiling.positions_mapped says that `positions` is a file mapping (a spill file) whose pages may
/// be dropped once read; never set it for positions in a vector.
/// Throws prt::Error as pca_normals() and tiled_knn() do.
void pca_normals_tiled(std::span<const std::array<double, 3>> positions, std::uint32_t k,
                       TiledKnnParams tiling, std::span<pool::Float3> normals, TiledKnnStats* stats = nullptr,
                       const std::function<void(std::uint64_t)>& progress = {},
                       const std::array<double, 3>* centre = nullptr);

}  // namespace prt::pre::import
