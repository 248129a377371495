// PointRT prt-import: what goes through PCL. PCL headers are heavy, so they are included by
// pcl_backend.cpp alone; builds without PCL compile pcl_missing.cpp instead, whose functions fail
// with one line saying the build lacks PCL.
#pragma once

#include <filesystem>
#include <vector>

#include "import.h"
#include "orient.h"

namespace prt::pre::import {

/// Reads a PCD file (ascii, binary, binary_compressed) with PCL: fields x y z required;
/// normal_x normal_y normal_z and rgb or rgba (packed in a float or uint32) used when present;
/// other fields skipped and listed in a note. Entries with a NaN x, y or z (the holes of an
/// organized cloud) are dropped and counted in report.nan_entries.
PointCloud read_pcd(const std::filesystem::path& path, Report& report, bool quiet);

/// PCA normals over the k nearest neighbours (PCL NormalEstimationOMP): Hoppe et al. 1992, sec.
/// 3.2, the tangent plane is the least-squares plane of the k nearest points, its normal the
/// eigenvector of their covariance with the smallest eigenvalue (thesis 3.1 takes splat radii from
/// the same k-NN neighbourhoods). Unoriented: the sign is whatever PCL's viewpoint rule gave
/// and must be fixed by orient.h. Points whose neighbourhood is degenerate get a NaN normal. When
/// `graph` is not null it receives the k-NN graph (k nearest OTHER points) for orientation.
/// Positions are searched relative to the bounding-box centre, in float, as PCL requires.
void estimate_normals(const PointCloud& cloud, int k, std::vector<pool::Float3>& normals, KnnGraph* graph,
                      bool quiet);

}  // namespace prt::pre::import
