// Test-only: a point cloud written as an input pool for the tools' end-to-end tests.
#pragma once

#include <string>

#include "point_cloud.h"
#include "prt/formats/pool.h"

namespace prt::test {

/// Writes `c`'s point sections (pre::write_point_sections) and a provenance entry of step "test"
/// to `path`; returns `path`.
inline std::string write_cloud_pool(const pre::PointCloud& c, const std::string& path) {
    pool::PoolWriter w;
    pre::write_point_sections(c, w);
    w.add_provenance("test", "0", "{}");
    w.write(path);
    return path;
}

}  // namespace prt::test
