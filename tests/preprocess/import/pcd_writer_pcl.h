// Test helper (PCL builds only): PCD files written by PCL itself.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace prt_import_test {

struct PcdPoint {
    float x, y, z;
    std::uint8_t r, g, b;
};

/// An organized width x height cloud of PointXYZRGB saved as binary_compressed.
void write_compressed_pcd(const std::string& path, const std::vector<PcdPoint>& points, std::uint32_t width,
                          std::uint32_t height);

}  // namespace prt_import_test
