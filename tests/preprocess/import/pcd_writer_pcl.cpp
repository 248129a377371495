// Test helper: writes binary_compressed PCD files with PCL's own writer (the only test file that
// includes PCL headers, which are heavy).
#include "pcd_writer_pcl.h"

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

namespace prt_import_test {

void write_compressed_pcd(const std::string& path, const std::vector<PcdPoint>& points, std::uint32_t width,
                          std::uint32_t height) {
    pcl::PointCloud<pcl::PointXYZRGB> cloud;
    cloud.width = width;
    cloud.height = height;
    cloud.is_dense = false;
    cloud.resize(static_cast<std::size_t>(width) * height);
    for (std::size_t i = 0; i < points.size() && i < cloud.size(); ++i) {
        pcl::PointXYZRGB& p = cloud[i];
        p.x = points[i].x;
        p.y = points[i].y;
        p.z = points[i].z;
        p.r = points[i].r;
        p.g = points[i].g;
        p.b = points[i].b;
    }
    cloud.width = width;
    cloud.height = height;
    pcl::io::savePCDFileBinaryCompressed(path, cloud);
}

}  // namespace prt_import_test
