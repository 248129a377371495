// PointRT prt-import: pose lists for merged imports (--poses): which scans to read and the rigid
// transform that brings each into the merged frame. Two formats, both documented in
// preprocess/import/README.md ("Pose files"):
//   - Stanford .conf (Turk & Levoy's zipper / scanalyze): "bmesh FILE tx ty tz qi qj qk qr", a scan
//     point p maps to R(q)^-1 p + t, the scanner far away on the scan frame's +z side;
//   - a JSON pose list of ours: per scan a file, a 4x4 row-major matrix or a translation and a
//     quaternion (p' = R(q) p + t), and an optional sensor in the scan's own frame.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "prt/formats/pool_layout.h"

namespace prt::pre::import {

/// A rigid transform p' = r p + t (r a rotation: orthonormal, determinant +1).
struct Rigid {
    double r[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    double t[3] = {0, 0, 0};

    std::array<double, 3> apply(const std::array<double, 3>& p) const {
        return {r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2] + t[0],
                r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2] + t[1],
                r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2] + t[2]};
    }
    std::array<double, 3> rotate(const std::array<double, 3>& d) const {
        return {r[0][0] * d[0] + r[0][1] * d[1] + r[0][2] * d[2],
                r[1][0] * d[0] + r[1][1] * d[1] + r[1][2] * d[2],
                r[2][0] * d[0] + r[2][1] * d[1] + r[2][2] * d[2]};
    }
    /// A sensor of the scan's frame in the merged frame (a point moves, a direction turns).
    pool::Sensor apply(const pool::Sensor& s) const;
    bool is_identity() const;
};

/// Quaternions are accepted when their norm is within this of 1, then normalised (pose files,
/// PCD VIEWPOINT): text rounded to 4 significant digits passes, a typo or a zero does not.
inline constexpr double k_quaternion_tolerance = 1e-3;
/// Matrices must be rigid to this: |R^T R - I| and |det R - 1| per entry, last row 0 0 0 1.
inline constexpr double k_rigid_tolerance = 1e-6;

/// The rotation of the unit quaternion w + x i + y j + z k (Hamilton convention, as Eigen and PCL).
/// The caller checks the norm; this normalises.
Rigid rotation_from_quaternion(double w, double x, double y, double z);

/// One scan of a pose list.
struct PoseEntry {
    std::filesystem::path file;          ///< resolved against the pose file's folder
    Rigid pose;                          ///< scan frame -> merged frame
    bool sensor_given = false;           ///< the entry says which sensor (else: the file's own)
    std::optional<pool::Sensor> sensor;  ///< in the scan's own frame; empty with sensor_given: none
    std::string where;                   ///< "POSES: line N" or "POSES: scans[i]", for messages
};

/// Reads a pose list: Stanford .conf by extension ".conf", JSON by ".json", else by the first
/// character that is not white space ('{' JSON). Checks every entry (counts, numbers finite,
/// quaternions unit within k_quaternion_tolerance, matrices rigid within k_rigid_tolerance, every
/// scan file present) and throws prt::Error "POSES: line N: what" or "POSES: scans[i]: what" on the
/// first problem. At least one scan.
std::vector<PoseEntry> read_poses(const std::filesystem::path& path);

/// read_poses(), then only the entries of the scan files in `only` (in that order; all when empty):
/// throws prt::Error "FILE: not listed in the pose file POSES" for a file the list lacks.
std::vector<PoseEntry> read_poses(const std::filesystem::path& path,
                                  const std::vector<std::filesystem::path>& only);

}  // namespace prt::pre::import
