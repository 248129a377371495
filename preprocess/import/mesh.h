// PointRT prt-import: meshes as point sets. Reading (OpenMesh, mesh_openmesh.cpp) fills a plain
// MeshData; the geometry here (vertex normals, surface sampling) is ours and needs no OpenMesh.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "import.h"

namespace prt::pre::import {

/// A polygon mesh as read from a file: faces are index lists (any size >= 3), no connectivity
/// structure, so non-manifold faces and repeated vertices are kept exactly as the file has them.
struct MeshData {
    std::vector<std::array<double, 3>> vertices;
    std::vector<std::uint32_t> face_begin;     ///< face f uses face_indices[face_begin[f], face_begin[f+1])
    std::vector<std::uint32_t> face_indices;   ///< vertex indices, in the file's winding order
    std::vector<pool::Float3> vertex_normals;  ///< from the file, or empty
    std::vector<pool::Rgba8> vertex_colors;    ///< from the file, or empty

    std::size_t face_count() const { return face_begin.empty() ? 0 : face_begin.size() - 1; }
};

/// Checks a mesh file's header against its size before OpenMesh sees it (OpenMesh trusts header
/// counts; garbled ones can make it loop): PLY with our reader (and a text-only header), ASCII OFF
/// counts and body as OpenMesh tokenises them (binary OFF and '#' comments refused), STL binary
/// size or "solid", OBJ faces whose first corner has a vertex index (OpenMesh asserts otherwise)
/// and mtllib lines naming no device or FIFO (OpenMesh reads them to the end).
/// Throws prt::Error "PATH: ...".
void precheck_mesh_file(const std::filesystem::path& path);

/// Reads a PLY/OBJ/OFF/STL mesh through OpenMesh (requires have_openmesh()). Faces with an invalid
/// vertex index or fewer than 3 vertices are skipped and counted in report.faces_invalid.
MeshData read_mesh(const std::filesystem::path& path, Report& report, bool quiet);

/// Twice the vector area of face f: the sum over its edges of v_i x v_{i+1} (Newell's method). Its
/// length is twice the face's area and its direction the face normal (right-hand rule on the
/// winding); exact for triangles, the area-weighted mean normal for non-planar polygons.
std::array<double, 3> face_area_vector(const MeshData& mesh, std::size_t f);

/// A vertex's summed area vector shorter than this times the sum of its faces' area-vector lengths
/// is cancellation (double-sided faces), not a direction.
inline constexpr double k_cancelled_normal = 1e-6;

/// Area-weighted vertex normals: for each vertex, the sum of the normals of the faces around it
/// weighted by their areas (= the sum of face_area_vector), normalised. Vertices on no face, or
/// whose faces cancel out (see k_cancelled_normal), get {0,0,0} (clean() drops them as zero normals).
std::vector<pool::Float3> area_weighted_normals(const MeshData& mesh);

/// The mesh's vertices as points. Normals area-weighted, with the file's vertex normal where the
/// faces give none (cancelled); or, when `file_normals`, the file's with area weighting where the
/// file gives none. Vertices with neither get {0,0,0} (dropped by clean()). Colors when the file has
/// them. Counts vertices on no face, cancelled normals and fallbacks in `report`.
PointCloud mesh_vertices(const MeshData& mesh, bool file_normals, Report& report);

/// `count` points uniformly distributed over the surface by area (polygons split into triangle
/// fans; a triangle is chosen with probability proportional to its area, then a point uniformly in
/// it by the square-root barycentric mapping). Deterministic for a given seed. Normals per `mode`;
/// colors interpolated from the vertex colors when the file has them.
PointCloud sample_mesh(const MeshData& mesh, std::uint64_t count, std::uint64_t seed, SampleNormals mode);

}  // namespace prt::pre::import
