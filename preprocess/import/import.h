// PointRT prt-import: turns scans (PLY, XYZ, PCD) and meshes (PLY with faces, OBJ, OFF, STL) into
// the point set of a pool: positions, normals (estimated when missing), colors, radii.
//
//   file --read--> PointCloud --clean()--> [PCA normals + orientation] --clean()--> pool sections
//
// Readers: PLY and XYZ are our own (memory-mapped, no per-property virtual dispatch); PCD goes
// through PCL and meshes through OpenMesh, each confined to one translation unit and optional in
// the build (PRT_WITH_PCL, PRT_WITH_OPENMESH): without them those paths fail with one clear line.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "point_cloud.h"

namespace prt::pre::import {

/// --format: how to read the input.
enum class Format {
    automatic,  ///< by extension (.ply .pcd .xyz .txt .obj .off .stl), else by the first bytes
    ply,        ///< our PLY reader (point set; see MeshMode for PLY files with faces)
    pcd,        ///< PCL's PCD reader
    xyz,        ///< text: "x y z" or "x y z nx ny nz" per line
    mesh,       ///< OpenMesh: PLY/OBJ/OFF/STL with faces
};

/// --normals: where normals come from.
enum class NormalsMode {
    automatic,  ///< keep the file's normals; estimate (PCA) only when the file has none
    keep,       ///< never estimate: keep the file's normals, or write none when it has none
    estimate,   ///< always estimate by PCA, ignoring any normals in the file
};

/// --mesh-mode: what a PLY file that has faces becomes.
enum class MeshMode {
    automatic,  ///< mesh when it has faces and no vertex normals (faces give better normals than
                ///< PCA), points otherwise; points when the build lacks OpenMesh
    points,     ///< always the vertex element as a point set (faces skipped)
    mesh,       ///< always through OpenMesh (area-weighted normals or --sample)
};

/// --sample-normals: normals of points sampled on a mesh surface.
enum class SampleNormals {
    face,          ///< the normal of the face the sample lies on (exact for the piecewise-flat mesh)
    interpolated,  ///< barycentric blend of the area-weighted vertex normals (smooth shading)
};

/// Everything prt-import's command line controls (the defaults are the tool's defaults).
struct Options {
    Format format = Format::automatic;
    NormalsMode normals = NormalsMode::automatic;
    MeshMode mesh_mode = MeshMode::automatic;
    std::uint64_t sample = 0;  ///< meshes: > 0 samples this many points over the surface by area
    std::uint64_t seed = 1;    ///< random seed for --sample (same seed, same points)
    SampleNormals sample_normals = SampleNormals::face;
    int k = 16;                                   ///< neighbours for PCA normals and orientation
    std::optional<std::array<double, 3>> sensor;  ///< orient normals toward this point
    bool keep_duplicates = false;                 ///< keep exactly coincident points
    bool quiet = true;                            ///< no progress on stderr
};

/// What happened during an import, for the user (stderr) and the tests. Every dropped point is
/// counted here or in `clean`.
struct Report {
    std::string reader;                 ///< e.g. "ply (binary_little_endian)", "mesh (OpenMesh, obj)"
    std::vector<std::string> notes;     ///< skipped properties/elements, warnings, one line each
    std::uint64_t records = 0;          ///< points (or vertices, or samples) the reader produced
    std::uint64_t nan_entries = 0;      ///< PCD: entries with NaN x/y/z (organized-cloud holes), dropped
    std::uint64_t malformed_lines = 0;  ///< XYZ: lines that are not 3 or 6 numbers, dropped
    std::uint64_t faces = 0;            ///< meshes: faces read
    std::uint64_t faces_invalid = 0;    ///< meshes: faces skipped (bad vertex index, < 3 vertices)
    std::uint64_t unreferenced_vertices = 0;  ///< meshes: vertices on no face (no area-weighted normal)
    std::uint64_t cancelled_normals = 0;  ///< meshes: vertices whose face normals cancel (double-sided faces)
    std::uint64_t fallback_normals = 0;   ///< meshes: vertices that took their normal from the other source
    CleanReport clean;                    ///< the first clean() over the points as read
    bool normals_from_file = false;
    bool normals_area_weighted = false;  ///< mesh vertices: sum of face normals weighted by area
    bool normals_estimated = false;      ///< PCA (k-NN) normals
    std::uint64_t estimate_failed = 0;   ///< PCA gave no normal (degenerate neighbourhood): dropped
    std::uint64_t components = 0;        ///< orientation by propagation: k-NN graph components
    std::uint64_t ambiguous = 0;         ///< orientation: points whose sign is a guess (see orient.h)
    bool oriented_to_sensor = false;
    std::string normals_detail;  ///< where the normals came from, one line
    std::uint64_t written = 0;   ///< points in the result
    double read_seconds = 0;
    double normals_seconds = 0;
    /// The lines printed on stderr after an import (notes, counts), without the trailing newline.
    std::vector<std::string> summary_lines() const;
};

/// Format a file would be read as under Format::automatic (by extension, then by content).
/// Throws prt::Error "PATH: ..." when neither tells.
Format detect_format(const std::filesystem::path& path);

/// Reads `path` into a cleaned point set (world frame, unit normals unless NormalsMode::keep found
/// none), filling `report`. Throws prt::Error "PATH: what is wrong" on unreadable or invalid input,
/// on input that leaves no points, and on paths this build lacks (PCL, OpenMesh).
PointCloud import_file(const std::filesystem::path& path, const Options& options, Report& report);

/// The parameters of an import as a JSON object text (for the pool's provenance section).
std::string options_json(const std::filesystem::path& input, const Options& options);

/// Whether this build has PCL (PCD import, normal estimation) and OpenMesh (mesh import).
bool have_pcl();
bool have_openmesh();

}  // namespace prt::pre::import
