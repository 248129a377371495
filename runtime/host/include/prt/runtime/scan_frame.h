// PointRT runtime (host): where a scan is and which way is up, for the default view of a pool
// (issue 15: real scans have outliers, uneven extents and no agreed up axis).
//
// - robust_bounds(): the box a camera should frame: per axis the 1st-99th percentile of the points,
//   grown to every point near it, so far outliers are left out and thin extremities kept.
// - detect_up(): the up direction from the data (prt-play --up auto): the normal of a dominant plane
//   (a floor, a table top; RANSAC, Fischler and Bolles 1981), else the normal of the plane the
//   scanners' directions span (a turntable), else +y.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "prt/formats/pool_layout.h"
#include "prt/vec3.h"

namespace prt::rt {

using DVec3 = Vec3d;

/// An axis-aligned box; `valid` is false for an empty point set.
struct Box {
    DVec3 lo{0, 0, 0}, hi{0, 0, 0};
    bool valid = false;
    std::uint64_t outside = 0;  ///< points of the sample left outside the box
};

/// Robust bounds of a point sample: per axis the 1st and 99th percentiles (nearest rank) give a
/// box B; the result is the bounds of every point inside B grown by `reach` x B's diagonal on each
/// side. Far outliers (a stray stereo match metres away) stay out; the parts of the model beyond
/// the percentiles (ear tips, a table's far corner) stay in. `kept`, when given, receives the
/// points inside.
Box robust_bounds(const std::vector<DVec3>& points, double reach = 0.25, std::vector<DVec3>* kept = nullptr);

/// Which rule decided the up direction (detect_up).
enum class UpRule {
    plane,         ///< the normal of a dominant plane (a floor, a table top)
    sensor_plane,  ///< the normal of the plane the scanners' directions span (a turntable)
    fallback,      ///< neither: +y
};

/// The points, normals and sensors of one pool (its local frame: positions are offsets from
/// `origin`; sensors are in the pool's world frame, as pool_layout.h stores them).
struct UpInput {
    std::span<const pool::Float3> positions;
    std::span<const pool::Float3> normals;  ///< may be empty
    std::span<const pool::Sensor> sensors;  ///< may be empty
    DVec3 origin{0, 0, 0};                  ///< ModelInfo::origin
};

/// Thresholds of detect_up (the defaults are the documented ones).
struct UpParams {
    std::uint32_t sample = 20000;     ///< points drawn (with a fixed seed) for RANSAC
    std::uint32_t iterations = 500;   ///< RANSAC trials (3 points each)
    double tolerance = 0.01;          ///< plane inlier distance, x the robust box's diagonal
    double normal_degrees = 30;       ///< inliers' normals within this angle of the plane's (when known)
    double min_plane_fraction = 0.2;  ///< a plane is dominant when it holds this fraction of the points
    double sensor_degrees = 5;        ///< sensor directions within this of a common plane
    double snap_degrees = 3;          ///< snap to the nearest axis within this angle
    std::uint64_t seed = 0x5eed;
};

/// What detect_up found.
struct UpDetection {
    DVec3 up{0, 1, 0};  ///< unit, in the pool's frame (world orientation)
    UpRule rule = UpRule::fallback;
    double plane_fraction = 0;   ///< the largest plane's share of the sampled points
    DVec3 plane_point{0, 0, 0};  ///< the centroid of that plane's inliers (pool's local frame)
    bool snapped = false;        ///< up was snapped to an axis
    std::string description;     ///< one line: the rule and why (for stderr)
};

/// The up direction of a scan: (1) a plane holding at least min_plane_fraction of the points (and,
/// with normals, points whose normals agree with it) gives its normal, pointing toward the sensors
/// when the pool has any; else toward the side of what stands on it (the points off the plane over
/// its own footprint: a scanner above a table sees the mug on it, never what is under it, while the
/// floor seen beyond the table's edge lies outside the footprint), when one side has at least twice
/// the other's (+20); else toward the side most other points lie on; else toward +y;
/// (2) else, when at least 3 sensor directions (point sensors: the direction from the points'
/// centre to the sensor), and at least half of them, lie within sensor_degrees of one plane and
/// spread over it (a turntable), the normal of that plane, pointing toward the side those sensors
/// lean to (scanners look down on a turntable), else toward the side more of the surface normals
/// face (the face the object rested on was never seen), else the side of +y; (3) else +y.
/// A result within snap_degrees of an axis is snapped to it.
UpDetection detect_up(const UpInput& in, const UpParams& params = {});

/// The axis name of a unit vector ("+y", "-z") or its components ("(0.12, -0.80, -0.59)").
std::string direction_name(const DVec3& v);

}  // namespace prt::rt
