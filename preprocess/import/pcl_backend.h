// PointRT prt-import: what goes through PCL (PCD reading). PCL headers are heavy, so they are
// included by pcl_backend.cpp alone; builds without PCL compile pcl_missing.cpp instead, whose
// functions fail with one line saying the build lacks PCL. Normal estimation is ours (neighbours.h).
#pragma once

#include <filesystem>
#include <vector>

#include "import.h"

namespace prt::pre::import {

/// Reads a PCD file (ascii, binary, binary_compressed) with PCL: fields x y z required;
/// normal_x normal_y normal_z, rgb or rgba (packed in a float or uint32) and intensity (any
/// numeric type) used when present; other fields skipped and listed in a note. A VIEWPOINT line
/// gives a point sensor at its translation (PCL's sensor_origin_). Entries with a NaN x, y or z
/// (the holes of an organized cloud) are dropped and counted in report.nan_entries.
PointCloud read_pcd(const std::filesystem::path& path, Report& report, bool quiet);

}  // namespace prt::pre::import
