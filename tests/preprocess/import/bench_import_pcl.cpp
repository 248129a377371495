#include <pcl/console/print.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include "bench_import.h"

namespace prt_bench {

std::uint64_t read_with_pcl(const std::string& path) {
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
    pcl::PLYReader reader;
    pcl::PointCloud<pcl::PointNormal> cloud;
    if (reader.read(path, cloud) < 0) return 0;
    return cloud.size();
}

}  // namespace prt_bench
