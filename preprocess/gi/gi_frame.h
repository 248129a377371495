// PointRT preprocess: where a model's GI octrees (caustics, thesis 5.4.2; light map, thesis 5.3)
// live, whatever surface the renderer traces it as (issue 20: splats, bricks, ISO, MLS, patches),
// and the points on its surface that light-map samples are drawn from.
//
// The frame is the root cube the GI octree's cells divide and the reference level the tools'
// --caustic-levels (below) and --levels-above (above) count from:
//   - a splat octree (prt-octree) or a bricked tree (prt-bricks): its root cube and depth, as before;
//   - otherwise the model's surface points (its own points for an ISO or MLS model, points sampled on
//     the patches for a patch model): the cube over their bounding box, grown by 1/64 of its edge on
//     every side (an ISO or MLS surface may pass a little outside the points), and the first level at
//     which the occupied cells hold at most k_points_per_cell points on average. On uniformly
//     sampled surfaces that is the splat octree's depth within one level (tested): the octree splits
//     a leaf past 48 replicated splats, about 6 per point.
// Patch models have no points: their surface is sampled on an n x n parameter grid per patch
// (n from the patch's area, about k_patch_samples points in all), each with the patch normal (the side its
// parametrization gives: consistent only for patch pools made with prt-patches --orient).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "prt/core/math.h"
#include "prt/formats/pool.h"

namespace prt::gi {

/// Points on a model's surface with unit normals, local frame.
struct SurfacePoints {
    std::vector<core::Vec3> position, normal;
    /// True when the points lie on the traced surface exactly (patch samples); false for a scan's
    /// points, which an ISO or MLS surface passes near, not through.
    bool on_surface = false;
    std::string from;  ///< "points", "patches"
};

/// Average occupied-cell population that ends the reference level's search.
inline constexpr double k_points_per_cell = 8.0;
/// Points sampled over a patch model's surface. Patches have no point spacing of their own, so this
/// sets their maps' resolution: about k_patch_samples / k_points_per_cell = 4096 occupied cells at the
/// reference level, whatever the model's size (a 2 x 2 floor gets 1/32-wide cells, as a splat floor
/// of 40 000 points does from its octree).
inline constexpr std::uint32_t k_patch_samples = 1u << 15;

/// The root cube and reference level of a model's GI octrees, and what they came from.
struct GiFrame {
    double root_min[3] = {0, 0, 0};
    double root_size = 1.0;
    std::uint32_t depth = 0;
    std::string from;  ///< "the splat octree", "the bricks", "the points", "the patches"
};

/// The model's surface points: its positions and normals when it has them, else samples on its
/// patches. Throws prt::Error "FILE: ..." when it has neither, or points without normals.
SurfacePoints surface_points(const pool::PoolFile& pool);

/// The model's GI frame (see the header comment). `points` is only read when the pool has no splat
/// octree and no bricks (then it must be surface_points(pool)).
GiFrame gi_frame(const pool::PoolFile& pool, const SurfacePoints* points);

/// Whether gi_frame needs the surface points (no splat octree, no bricks).
bool frame_needs_points(const pool::PoolFile& pool);

/// The first level (>= 1) at which the cells of the root cube occupied by `points` hold at most
/// `per_cell` points on average (capped at pool::k_max_gi_depth - 2, so caustic levels below it fit).
std::uint32_t reference_level(const std::vector<core::Vec3>& points, const double root_min[3],
                              double root_size, double per_cell = k_points_per_cell);

}  // namespace prt::gi
