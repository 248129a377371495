// PointRT prt-import: our own check of a PCD file's header and data size before PCL reads it.
// PCL's PCDReader trusts the header (a garbage header can crash it), so nothing reaches PCL unless
// the header is complete and consistent and the data is as long as the header says.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "import.h"

namespace prt {
class MappedFile;
}

namespace prt::pre::import {

struct PcdHeader {
    std::vector<std::string> fields;
    std::vector<std::uint32_t> size;   ///< bytes per value: 1, 2, 4 or 8
    std::vector<char> type;            ///< 'I', 'U' or 'F'
    std::vector<std::uint32_t> count;  ///< values per field (1 unless an array field)
    std::uint64_t width = 0, height = 0, points = 0;
    std::string data;              ///< "ascii", "binary" or "binary_compressed"
    std::size_t data_offset = 0;   ///< first byte after the DATA line
    std::uint64_t point_step = 0;  ///< bytes per point in the binary layouts
    /// VIEWPOINT tx ty tz qw qx qy qz: the sensor's pose in the cloud's frame (PCL's
    /// sensor_origin_ and sensor_orientation_); the quaternion normalised. Empty without the line.
    std::optional<std::array<double, 7>> viewpoint;
};

/// Parses and validates the header; checks the data holds the declared points (binary: the byte
/// count; binary_compressed: its size words; ascii: the line count). A VIEWPOINT line must hold 7
/// finite numbers with a unit quaternion (within k_quaternion_tolerance, poses.h); colour fields
/// (rgb, rgba) must be one 4-byte value and intensity one value per point. Throws prt::Error
/// "LABEL: ..."; data after the declared points is a warning in report.notes.
PcdHeader check_pcd(const MappedFile& file, Report& report);

}  // namespace prt::pre::import
