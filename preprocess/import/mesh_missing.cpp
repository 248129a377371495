// Built instead of mesh_openmesh.cpp when OpenMesh is absent (PRT_WITH_OPENMESH=OFF or not found).
#include "mesh.h"

namespace prt::pre::import {

bool have_openmesh() {
    return false;
}

MeshData read_mesh(const std::filesystem::path& path, Report&, bool) {
    throw_missing_library(
        path, "mesh import", "OpenMesh",
        "rebuild with PRT_WITH_OPENMESH=ON, or import a PLY's vertices with --mesh-mode points");
}

}  // namespace prt::pre::import
