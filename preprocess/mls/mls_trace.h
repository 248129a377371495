// PointRT: the MLS surface as the accuracy reference (DESIGN.md, "Surfaces"): hit distances,
// points and normals of a batch of rays on the CPU, multithreaded, through the same core functions
// the renderer calls (prt/core/mls.h). Benchmarks of splats and ISO compare their hits against
// trace_rays(view, rays, reference_params()). Host only.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "prt/core/mls.h"
#include "prt/core/ray.h"

namespace prt::mls {

/// Precision of the sums of F (core template parameter Real).
enum class Precision : std::uint32_t { single, dual };

/// Settings for reference hits: 16 samples per cell interval, 12 regula falsi steps, both faces,
/// sums in double. The root is then found to float resolution of t wherever a sign change is
/// bracketed (the remaining error is the sampling: two roots closer than a sample spacing in
/// one cell, i.e. grazing rays, are missed by any sampling method).
core::MlsParams reference_params();
inline constexpr Precision k_reference_precision = Precision::dual;

/// Sums of the per-ray statistics over a batch (WS05 4.3).
struct TraceTotals {
    std::uint64_t rays = 0, hits = 0;
    std::uint64_t traversal_steps = 0, cells = 0, intersections = 0, splats = 0, evaluations = 0;
    std::uint64_t truncated = 0;
    double seconds = 0;  ///< wall time of the batch
    void add(const core::MlsStats& s);
    double per_ray(std::uint64_t total) const { return rays ? double(total) / double(rays) : 0.0; }
    double rays_per_second() const { return seconds > 0 ? double(rays) / seconds : 0.0; }
};

/// Hits of a batch: found[i] != 0 when ray i hit; hits[i] then holds t, position, normal (model
/// local frame, outward normal), front, point.
struct TraceResult {
    std::vector<core::MlsHit> hits;
    std::vector<std::uint8_t> found;
    TraceTotals totals;
};

/// Traces every ray (model local frame; Ray::t_max bounds the hit, Ray::flags' k_ray_inside
/// selects the faces under k_mls_faces_by_ray) from `threads` threads (0 = all cores).
TraceResult trace_rays(const core::MlsView& view, std::span<const core::Ray> rays,
                       const core::MlsParams& params, unsigned threads = 0,
                       Precision precision = Precision::single);

/// Shadow-ray batch: occluded[i] != 0 when ray i meets the surface in [0, t_max).
std::vector<std::uint8_t> occluded_rays(const core::MlsView& view, std::span<const core::Ray> rays,
                                        const core::MlsParams& params, unsigned threads = 0,
                                        TraceTotals* totals = nullptr,
                                        Precision precision = Precision::single);

}  // namespace prt::mls
