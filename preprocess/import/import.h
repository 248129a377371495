// PointRT prt-import: turns scans (PLY, XYZ, PCD, pools) and meshes (PLY with faces, OBJ, OFF, STL)
// into the point set of a pool: positions, normals (estimated when missing, oriented toward the
// scanner when it is known), colors, intensities, radii, sensors.
//
//   per scan:  file --read--> PointCloud --clean()--> outlier removal --pose--> merged frame
//   then:      merge (scan_ids) --clean()--> [PCA normals + orientation] --clean()--> pool sections
//
// One scan (a file) or several (a pose list, --poses: poses.h). Readers: PLY and XYZ are our own
// (memory-mapped, no per-property virtual dispatch); PCD goes through PCL and meshes through
// OpenMesh, each confined to one translation unit and optional in the build (PRT_WITH_PCL,
// PRT_WITH_OPENMESH): without them those paths fail with one clear line. The k-NN search behind
// outlier removal, normals and orientation is ours (knn.h), the same in every build.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "neighbours.h"
#include "point_cloud.h"

namespace prt::pre::import {

/// --format: how to read the input.
enum class Format {
    automatic,  ///< by extension (.ply .pcd .xyz .txt .obj .off .stl), else by the first bytes
    ply,        ///< our PLY reader (point set; see MeshMode for PLY files with faces)
    pcd,        ///< PCL's PCD reader
    xyz,        ///< text: "x y z" or "x y z nx ny nz" per line
    mesh,       ///< OpenMesh: PLY/OBJ/OFF/STL with faces
    pool,       ///< a PointRT pool: its point sections (read_point_sections), provenance kept
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
    /// Neighbours for PCA normals and orientation. 24 by measurement (issue 15, prt-fidelity on
    /// the ten bunny scans: false hits of MLS 0.44 % -> 0.28 %, of the ISO 0.26 % -> 0.12 % against 16).
    int k = 24;
    std::optional<std::array<double, 3>> sensor;  ///< --sensor: one point sensor (output frame) for all
    std::optional<std::array<double, 3>> sensor_direction;  ///< --sensor-direction: one far sensor
    bool no_sensor = false;  ///< --no-sensor: ignore the files' and the pose list's sensors
    /// --grazing-cos: with a sensor, an estimated normal whose |cos| to its line of sight is below
    /// this is not oriented by its own sensor but takes its sign from the confidently oriented
    /// normals around it, over the k-NN graph (orient_by_propagation with those fixed); 0 orients
    /// every normal by its sensor alone. 0.3 (72.5 degrees) measured best over the ten bunny scans
    /// and the PCL mug scene together (preprocess/import/README.md, "Sensors and orientation").
    double grazing_cos = 0.3;
    /// With a sensor: orient by propagation (as without one), then turn each propagation component
    /// to face the sensors on the whole (the sum over its points of n . line of sight, unit).
    /// Measured and not chosen (README "Sensors and orientation"); library only, for prt-bench-scans.
    bool propagate_then_vote = false;
    OutlierParams outliers;        ///< statistical + radius outlier removal per scan (neighbours.h)
    bool keep_duplicates = false;  ///< keep exactly coincident points
    /// --keep-fraction: keep this fraction of each scan's points, chosen by a hash of (--seed, index)
    /// before anything else (decimation: the "10 %" models of issue 15's fidelity cases); 1 keeps all.
    double keep_fraction = 1.0;
    bool quiet = true;             ///< no progress on stderr
};

/// What happened during an import, for the user (stderr) and the tests. Every dropped point is
/// counted here or in `clean`.
struct Report {
    std::string label;                  ///< the file read (merged imports: per scan)
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
    OutlierReport outliers;               ///< outlier removal (per scan; merged: the sum)
    std::string sensor_source;            ///< where the file's sensor came from ("" when none)
    std::string sensors_detail;           ///< the sensors of the result, one line
    std::vector<Report> scans;            ///< merged imports: one report per scan
    std::vector<std::filesystem::path> pools;  ///< pool inputs (their provenance is kept)
    bool normals_from_file = false;
    bool normals_area_weighted = false;  ///< mesh vertices: sum of face normals weighted by area
    bool normals_estimated = false;      ///< PCA (k-NN) normals
    std::uint64_t estimate_failed = 0;   ///< PCA gave no normal (degenerate neighbourhood): dropped
    std::uint64_t components = 0;        ///< orientation by propagation: k-NN graph components
    std::uint64_t ambiguous = 0;         ///< orientation: points whose sign is a guess (see orient.h)
    std::uint64_t grazing_flipped = 0;   ///< grazing_cos: normals whose sign the neighbours changed
    bool oriented_to_sensor = false;
    std::string normals_detail;  ///< where the normals came from, one line
    std::uint64_t written = 0;   ///< points in the result
    std::uint64_t decimated = 0;  ///< points dropped by --keep-fraction
    double read_seconds = 0;
    double normals_seconds = 0;
    /// The lines printed on stderr after an import (notes, counts), without the trailing newline.
    std::vector<std::string> summary_lines() const;
};

/// Format a file would be read as under Format::automatic (by extension, then by content).
/// Throws prt::Error "PATH: ..." when neither tells.
Format detect_format(const std::filesystem::path& path);

/// Reads `path` into a cleaned point set (world frame, outliers removed, unit normals unless
/// NormalsMode::keep found none), filling `report`. A pool holding several scans (scan_ids) is
/// filtered scan by scan, like a merged import. Throws prt::Error "PATH: what is wrong" on
/// unreadable or invalid input, on input that leaves no points, and on paths this build lacks
/// (PCL, OpenMesh).
PointCloud import_file(const std::filesystem::path& path, const Options& options, Report& report);

/// Reads every scan of the pose list `poses` (poses.h), or only those of `only` when it is not
/// empty (each must be listed), each cleaned and rid of outliers in its own frame, moves them into
/// the merged frame and merges them: one sensor per scan and scan_ids when every scan has a sensor.
/// Normals are estimated over the merged points and oriented toward each point's own sensor.
/// Errors name the pose file and the line or entry, or the scan file.
PointCloud import_merged(const std::filesystem::path& poses, const std::vector<std::filesystem::path>& only,
                         const Options& options, Report& report);

/// The parameters of an import as a JSON object text (for the pool's provenance section).
std::string options_json(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& poses,
                         const Options& options);
inline std::string options_json(const std::filesystem::path& input, const Options& options) {
    return options_json(std::vector<std::filesystem::path>{input}, {}, options);
}

/// Whether this build has PCL (PCD import) and OpenMesh (mesh import).
bool have_pcl();
bool have_openmesh();

/// For the stubs built without PCL or OpenMesh: throws "PATH: WHAT needs LIBRARY, and this build
/// of prt-import has no LIBRARY (HINT)".
[[noreturn]] void throw_missing_library(const std::filesystem::path& path, const char* what,
                                        const char* library, const char* hint);

}  // namespace prt::pre::import
