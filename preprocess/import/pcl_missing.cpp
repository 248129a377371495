// Built instead of pcl_backend.cpp when PCL is absent (PRT_WITH_PCL=OFF or not found).
#include "pcl_backend.h"
#include "prt/error.h"

namespace prt::pre::import {

bool have_pcl() {
    return false;
}

PointCloud read_pcd(const std::filesystem::path& path, Report&, bool) {
    throw Error(path.string() +
                ": PCD import needs PCL, and this build of prt-import has no PCL "
                "(rebuild with PRT_WITH_PCL=ON)");
}

void estimate_normals(const PointCloud&, int, std::vector<pool::Float3>&, KnnGraph*, bool) {
    throw Error(
        "normal estimation needs PCL, and this build of prt-import has no PCL (rebuild with "
        "PRT_WITH_PCL=ON, or import a file with normals, or use --normals keep)");
}

}  // namespace prt::pre::import
