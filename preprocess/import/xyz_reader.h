// PointRT prt-import: XYZ text point sets.
#pragma once

#include <filesystem>

#include "import.h"

namespace prt::pre::import {

/// Reads "x y z" or "x y z nx ny nz" per line, values separated by spaces, tabs or commas; '#'
/// starts a comment; blank lines are ignored. The first line with 3 or 6 values fixes the column
/// count; other lines with another count or a value that is not a number are dropped and counted
/// (report.malformed_lines, with the first line numbers in a note). Fails when the file is empty,
/// binary, has no valid line, or more malformed lines than valid ones (it is not XYZ text).
PointCloud read_xyz(const std::filesystem::path& path, Report& report, bool quiet);

}  // namespace prt::pre::import
