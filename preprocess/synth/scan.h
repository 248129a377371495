// PointRT synthetic laser scans (issue 15): the points where a virtual terrestrial laser scanner's
// rays first hit an analytic shape of analytic.h, with exact truth for every return. What real scans
// have and uniform samples hide: scan-line anisotropy (dense along a line, sparse across), density
// falling with range and incidence, no returns at grazing incidence, range noise along the ray,
// mixed-pixel outliers, per-return intensity, several scanner positions, and no normals.
//
// The scan pattern is a terrestrial laser scanner's (a Leica or FARO on a tripod): the head turns
// about its axis (default +y) in azimuth steps of line_step; at each azimuth a mirror sweeps a
// vertical profile, the scan line, in elevation steps of sample_step. Both grids are multiples of
// their step from azimuth 0 / elevation 0 (a scanner's encoder), so scans of one scanner setting
// from different positions share the pattern. Outside the shape's bounding box the field is the
// cone of the shape's bounding sphere; inside it (the room, the ring's hole) the whole sphere but
// the blind cone below the scanner (its tripod).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analytic.h"
#include "point_cloud.h"
#include "synth.h"

namespace prt::synth {

struct ScanOptions {
    Shape shape;
    /// Scanner positions, world frame; each must be in the open (outside solids, inside the room's
    /// air, off the plane). Empty: default_scanners(shape, 1).
    std::vector<Vec3> scanners;
    Vec3 axis{0, 1, 0};                  ///< the head's rotation axis ("up"), any non-zero vector
    double sample_step_degrees = 0.025;  ///< along a scan line (elevation); > 0
    double line_step_degrees = 0.1;      ///< between scan lines (azimuth); > 0. Anisotropy: ratio.
    double blind_cone_degrees = 30;      ///< half angle of the unscanned cone below, full-sphere fields
    double max_incidence_degrees = 85;   ///< no return beyond this angle between ray and normal
    /// Grazing dropouts: a return at incidence i is lost with probability
    /// dropout * ((1 - cos i) / (1 - cos max_incidence))^2 (0 at normal incidence, `dropout` at the
    /// limit): a return's strength falls with cos i, so steep returns are missed more often. [0, 1].
    double dropout = 0;
    /// Range noise: Gaussian along the ray, sigma = range_noise * shape_size(shape)
    /// + range_noise_per_range * range, truncated at k_noise_truncation sigma.
    double range_noise = 0;
    double range_noise_per_range = 0;
    /// Mixed-pixel outliers: exactly round(outliers * returns) returns moved along their ray by
    /// +-U(0.05, 0.25) * size (either sign with probability 1/2; towards the scanner never closer
    /// than 10 % of the range). [0, 1].
    double outliers = 0;
    /// Uniform outliers: round(uniform_outliers * returns) more points, uniform in the shape's
    /// bounding box grown by 10 % of the size on every side, appended after the returns. [0, 1].
    double uniform_outliers = 0;
    /// Intensity = albedo(part) * cos(incidence) * (1 + intensity_noise * g), g standard normal
    /// truncated at k_noise_truncation, clamped to >= 0; uniform outliers get U(0, 1). [0, 1].
    double intensity_noise = 0.02;
    bool normals = false;  ///< write the true normal of each return (tests); real scans have none
    ColorMode colors = ColorMode::none;
    pool::Rgba8 color{200, 200, 200, 255};
    std::uint64_t seed = 1;
    unsigned threads = 0;  ///< 0 = all cores; the output does not depend on it
};

/// `count` scanners in the open, turned evenly about +y: outside the shape at 3 x shape_size from
/// its bounding box centre, at azimuth 30 + i 360 / count degrees (0: +z, 90: +x) and elevation 35
/// degrees; for the room inside it, at (0.3 sin t, 0.05, 0.3 cos t) x size from its centre,
/// t = i 360 / count (above both objects of the standard room, in its air). World frame.
std::vector<Vec3> default_scanners(const Shape& shape, std::size_t count);

/// Throws prt::Error naming the first invalid option ("--sample-step must be ...", "--scanner
/// X,Y,Z is inside the sphere ...") using the command line's option names.
void validate(const ScanOptions& options);

/// Per scanner: where it looked and what came back.
struct ScannerStats {
    Vec3 position{};
    bool full_field = false;  ///< whole sphere minus the blind cone (else the bounding cone)
    double azimuth_degrees[2] = {0, 0};
    double elevation_degrees[2] = {0, 0};
    std::uint64_t lines = 0;            ///< scan lines with at least one ray in the field
    std::uint64_t rays = 0;             ///< rays cast (inside the field)
    std::uint64_t misses = 0;           ///< rays that hit nothing
    std::uint64_t dropped_grazing = 0;  ///< hits beyond max_incidence: no return
    std::uint64_t dropped_dropout = 0;  ///< hits lost to the grazing dropout
    std::uint64_t returns = 0;          ///< points from this scanner (outliers included)
    std::uint64_t first = 0;            ///< index of its first point
};

struct ScanResult {
    /// World frame; sensors: one k_sensor_point per scanner; scan_ids when more than one scanner;
    /// intensities; normals only with ScanOptions::normals; flags has k_model_synthetic.
    pre::PointCloud cloud;
    std::vector<ScannerStats> scanners;
    std::uint64_t returns = 0;  ///< points from rays (mixed-pixel outliers included)
    /// Per point: the part its ray hit (analytic.h part numbering; -1 for uniform outliers).
    std::vector<std::int8_t> part;
    /// Per part name: returns that hit it, in part order (PartRange::first is unused: 0).
    std::vector<PartRange> parts;
    std::vector<std::uint64_t> outlier_indices;          ///< the displaced returns, ascending
    std::uint64_t uniform_first = 0, uniform_count = 0;  ///< the appended uniform outliers
    double range_sigma = 0;  ///< range_noise * size, world units (the range-independent part)
    /// Provenance parameters: {"shape", "mode": "scan", the pattern, every option, per scanner
    /// field and counts, totals, per-part returns, outlier indices (up to k_max_recorded_outliers)}.
    std::string parameters_json;
};

/// The provenance lists outlier indices up to this many (beyond: the count only).
inline constexpr std::uint64_t k_max_recorded_outliers = 1000000;

/// Casts every ray of every scanner. Deterministic: each ray's randomness is a function of (seed,
/// scanner, line, sample), the outliers are chosen by a seeded hash order, so the output is the same
/// for any thread count. `progress(done, total)` counts scan lines, from the calling thread only.
/// Throws prt::Error on invalid options, a pattern of more than 2^32 rays, or no return at all.
ScanResult scan(const ScanOptions& options,
                const std::function<void(std::uint64_t, std::uint64_t)>& progress = {});

}  // namespace prt::synth
