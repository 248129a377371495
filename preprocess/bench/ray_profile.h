// PointRT benchmarks: where the rays' work goes, measured on the host with the core's own
// functions (prt-bench --profile). For each bounce depth (0 = primary) and for shadow rays: rays,
// octree leaves visited, filled leaves passed by their bounds (LeafBounds), splat tests, per ray;
// and how evenly that work falls on the 32 threads of a warp (thesis 2.3: a warp traces an 8x4
// Z-order block of pixels), which bounds what a GPU gains from cheaper rays.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "prt/core/camera.h"
#include "prt/core/scene_view.h"

namespace prt::player {

/// Work of one kind of ray, summed over the frame.
struct RayWork {
    std::uint64_t rays = 0, leaves = 0, culled = 0, splat_tests = 0;
    double per_ray(std::uint64_t v) const { return rays ? static_cast<double>(v) / rays : 0.0; }
};

/// The profile of one frame.
struct RayProfile {
    std::vector<RayWork> depth;  ///< index = bounce depth, 0 = primary rays
    RayWork shadow;
    std::uint64_t dropped = 0;  ///< secondary rays dropped because the ray stack was full (RayCounters)
    /// SIMT efficiency of the walk steps (leaves) and splat tests: the work of the 32 threads of a
    /// warp over 32 x the work of its busiest thread, summed over warps; "per bounce" takes the
    /// busiest thread of every bounce depth separately (a warp waits at the end of each bounce's
    /// walk for its slowest ray), "whole path" only over the whole ray tree of each pixel (what a
    /// megakernel that never re-converges between bounces would reach).
    double leaves_simt_per_bounce = 0, leaves_simt_whole_path = 0;
    double tests_simt_per_bounce = 0, tests_simt_whole_path = 0;

    nlohmann::json to_json() const;
    /// A table, one line per ray kind, then the SIMT efficiencies.
    std::string table() const;
};

/// Traces every pixel of a width x height frame on the host (every core the process may use) with
/// core::trace_ray, recording the work of each ray.
RayProfile profile_rays(const core::SceneView& scene, const core::PinholeCamera& camera, std::uint32_t width,
                        std::uint32_t height);

}  // namespace prt::player
