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

}  // namespace prt::pre::import
