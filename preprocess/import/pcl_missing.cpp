// Built instead of pcl_backend.cpp when PCL is absent (PRT_WITH_PCL=OFF or not found).
#include "pcl_backend.h"

namespace prt::pre::import {

bool have_pcl() {
    return false;
}

PointCloud read_pcd(const std::filesystem::path& path, Report&, bool) {
    throw_missing_library(path, "PCD import", "PCL", "rebuild with PRT_WITH_PCL=ON");
}

}  // namespace prt::pre::import
