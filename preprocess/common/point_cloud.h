// PointRT preprocess: the in-memory point set every tool reads from and writes to a pool.
// Positions are double in memory (world frame); the pool stores them as float offsets from the
// bounding-box centre (ModelInfo::origin), see write_point_sections().
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "prt/formats/pool.h"

namespace prt::pre {

/// A point set. Optional attributes are either empty or have positions.size() elements.
struct PointCloud {
    std::vector<std::array<double, 3>> positions;  ///< world frame
    std::vector<pool::Float3> normals;             ///< unit, or empty
    std::vector<pool::Rgba8> colors;               ///< or empty
    std::vector<float> radii;                      ///< splat radii, world units, or empty
    std::vector<float> intensities;                ///< scanner return intensity as read, or empty
    std::vector<std::uint16_t> scan_ids;           ///< index into sensors per point, or empty
    std::vector<pool::Sensor> sensors;             ///< the scans' sensors (world frame), or empty
    std::uint32_t flags = 0;                       ///< pool::ModelFlags

    std::size_t size() const { return positions.size(); }
    bool has_normals() const { return !normals.empty(); }
    bool has_colors() const { return !colors.empty(); }
    bool has_radii() const { return !radii.empty(); }
    bool has_intensities() const { return !intensities.empty(); }
    bool has_scan_ids() const { return !scan_ids.empty(); }
};

/// Counts of points dropped or repaired while cleaning input: never silent (issue: bad input).
struct CleanReport {
    std::uint64_t input = 0;        ///< points read
    std::uint64_t non_finite = 0;   ///< dropped: NaN/Inf coordinates
    std::uint64_t zero_normal = 0;  ///< dropped: zero-length or non-finite normal
    std::uint64_t duplicates = 0;   ///< dropped: exactly coincident with an earlier point
    std::uint64_t kept = 0;
    std::string summary() const;  ///< one line for stderr
};

/// The hash clean() sorts positions by to find exact duplicates (-0 as +0; equal positions, equal
/// hashes): shared with the out-of-core import's duplicate buckets.
std::uint64_t position_hash(const std::array<double, 3>& p);

/// Drops non-finite points, points whose normal is zero or non-finite (when normals are present;
/// other normals are renormalised) and exact duplicates (keeping the first), on every core the
/// process may use. Keeps attributes aligned.
/// `kept`, when not null, receives the original index of every point kept, in order.
CleanReport clean(PointCloud& cloud, bool drop_duplicates = true, std::vector<std::size_t>* kept = nullptr);

/// Keeps the points whose `keep[i]` is non-zero, in order, every per-point attribute aligned; returns
/// how many are kept. `kept`, when not null, receives the original index of every point kept.
std::size_t keep_points(PointCloud& cloud, const std::vector<std::uint8_t>& keep,
                        std::vector<std::size_t>* kept = nullptr);

/// Axis-aligned bounds of the positions (world frame); {+inf, -inf} when empty.
std::array<std::array<double, 3>, 2> bounds(const PointCloud& cloud);

/// Adds model_info, positions and whichever of normals/colors/radii/intensities/scan_ids/sensors the
/// cloud has to `writer` (replacing any present, removing the absent ones). The local origin is the
/// bounding-box centre. Throws on an empty cloud.
void write_point_sections(const PointCloud& cloud, pool::PoolWriter& writer);

/// Reads the point sections of a pool back to world-frame doubles.
PointCloud read_point_sections(const pool::PoolFile& pool);

}  // namespace prt::pre
