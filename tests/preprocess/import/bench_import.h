// prt-bench-import: the other readers, each in its own translation unit (heavy headers).
#pragma once

#include <cstdint>
#include <string>

namespace prt_bench {

/// Reads `path` with pcl::PLYReader into a PointCloud<PointNormal>; returns the points read.
std::uint64_t read_with_pcl(const std::string& path);

/// Reads `path` with OpenMesh::IO::read_mesh into a TriMesh with vertex normals; returns vertices.
std::uint64_t read_with_openmesh(const std::string& path);

}  // namespace prt_bench
