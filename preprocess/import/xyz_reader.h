// PointRT prt-import: XYZ text point sets.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>

#include "import.h"

namespace prt::pre::import {

/// Reads "x y z" or "x y z nx ny nz" per line, values separated by spaces, tabs or commas; '#'
/// starts a comment; blank lines are ignored. The first line with 3 or 6 values fixes the column
/// count; other lines with another count or a value that is not a number are dropped and counted
/// (report.malformed_lines, with the first line numbers in a note). Fails when the file is empty,
/// binary, has no valid line, or more malformed lines than valid ones (it is not XYZ text).
PointCloud read_xyz(const std::filesystem::path& path, Report& report, bool quiet);

/// read_xyz() streaming (out of core, issue 17): the points are handed to `flush` in file order, at
/// most `chunk` at a time, and the pages of the mapped file read so far leave the resident set.
/// The checks on the whole file (no valid line, more malformed lines than valid ones) throw at the
/// end, after the chunks were handed over. Returns a point set without points.
PointCloud read_xyz_chunks(const std::filesystem::path& path, Report& report, bool quiet, std::size_t chunk,
                           const std::function<void(const PointCloud&)>& flush);

}  // namespace prt::pre::import
