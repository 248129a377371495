// PointRT prt-import: our own check of a PCD file's header and data size before PCL reads it.
// PCL's PCDReader trusts the header (a garbage header can crash it), so nothing reaches PCL unless
// the header is complete and consistent and the data is as long as the header says.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "import.h"

namespace prt::pre::import {

class MappedFile;

struct PcdHeader {
    std::vector<std::string> fields;
    std::vector<std::uint32_t> size;   ///< bytes per value: 1, 2, 4 or 8
    std::vector<char> type;            ///< 'I', 'U' or 'F'
    std::vector<std::uint32_t> count;  ///< values per field (1 unless an array field)
    std::uint64_t width = 0, height = 0, points = 0;
    std::string data;              ///< "ascii", "binary" or "binary_compressed"
    std::size_t data_offset = 0;   ///< first byte after the DATA line
    std::uint64_t point_step = 0;  ///< bytes per point in the binary layouts
};

/// Parses and validates the header; checks the data holds the declared points (binary: the byte
/// count; binary_compressed: its size words; ascii: the line count). Throws prt::Error "LABEL: ...";
/// data after the declared points is a warning in report.notes.
PcdHeader check_pcd(const MappedFile& file, Report& report);

}  // namespace prt::pre::import
