// prt-patches: readers for bicubic Bezier patch files (the .bpt text format and the Newell format).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "prt/formats/patch_layout.h"

namespace prt::patches {

/// Patch file formats prt-patches reads.
enum class PatchFormat {
    automatic,  ///< .bpt by extension, else by content (a "3 3" degree line after the count)
    bpt,        ///< count; per patch a line "3 3" (degrees) and 16 lines "x y z"
    newell,     ///< count P; P lines of 16 comma-separated 1-based vertex indices (4x4 net, row
                ///< major); vertex count V; V lines "x,y,z" (the Utah teapot's original format)
};

/// "auto", "bpt" or "newell" to a PatchFormat (throws prt::Error otherwise).
PatchFormat parse_patch_format(const std::string& name);
const char* patch_format_name(PatchFormat format);

/// The patches of one file, in the file's coordinates.
struct PatchSet {
    std::vector<pool::PatchControlNet> nets;      ///< net row r, column c -> p[4 r + c]
    PatchFormat format = PatchFormat::automatic;  ///< the format actually read
};

/// Parses patch file text. Any problem (wrong counts, an index out of range, a non-number, a NaN
/// or infinite coordinate, a missing or extra line) throws prt::Error with one line
/// "LABEL:LINE: what is wrong"; counts above pool::k_max_patches are refused before allocating.
PatchSet parse_patches(std::string_view text, const std::string& label, PatchFormat format);

/// Reads and parses a patch file (errors name the path).
PatchSet read_patch_file(const std::filesystem::path& path, PatchFormat format);

}  // namespace prt::patches
