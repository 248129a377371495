#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "bench_import.h"

namespace prt_bench {

std::uint64_t read_with_openmesh(const std::string& path) {
    OpenMesh::TriMesh_ArrayKernelT<> mesh;
    mesh.request_vertex_normals();
    OpenMesh::IO::Options options(OpenMesh::IO::Options::VertexNormal);
    if (!OpenMesh::IO::read_mesh(mesh, path, options)) return 0;
    return mesh.n_vertices();
}

}  // namespace prt_bench
