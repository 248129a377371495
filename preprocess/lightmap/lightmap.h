// PointRT prt-lightmap (thesis 5.3): a diffuse light map per model: surface samples (the model's
// own points, a few per light-map leaf) whose indirect irradiance is path traced over the scene
// (lightmap_trace.h), gathered at the corners of a light-map octree with the weighted average of
// eq. 5.3-5.4 and rejection of samples whose normals disagree with the leaf's.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "gi_build.h"
#include "prt/core/lightmap.h"
#include "prt/core/scene_view.h"
#include "prt/formats/pool.h"

namespace prt::lightmap {

// The device-callable gathering lives in the core (prt/core/lightmap.h).
using core::indirect_irradiance;
using TraceParams = core::LightMapTraceParams;

/// One surface sample: where (local frame of its model, and render frame), which side, and the
/// indirect irradiance traced there.
struct Sample {
    float position[3];  ///< local frame
    float normal[3];    ///< local frame, unit
    core::Vec3 render_position, render_normal;
    float irradiance[3] = {0, 0, 0};
};

/// Picks at most `per_leaf` of the model's points in every cell at `depth` (evenly spread over the
/// cell's points in their pool order) as samples; `model` places them in the render frame.
std::vector<Sample> select_samples(const pool::PoolFile& pool, const core::ModelView& model,
                                   const double root_min[3], double root_size, std::uint32_t depth,
                                   std::uint32_t per_leaf);

/// Traces every sample's indirect irradiance (CPU threads). `progress(done, total)` from the
/// calling thread.
void trace_samples(const core::SceneView& scene, const TraceParams& params, std::span<Sample> samples,
                   std::uint64_t first_index, unsigned threads,
                   const std::function<void(std::uint64_t)>& progress = {});

struct GatherOptions {
    std::uint32_t depth = 8;    ///< light-map leaf level
    float radius_edges = 1.5f;  ///< gather radius g in leaf edges
    float reject_cos = 0.5f;  ///< samples whose normal makes a cosine below this with the leaf's are rejected
    float lookup_cos = 0.0f;  ///< GiInfo::cos_threshold
    unsigned threads = 0;
};

/// thesis 5.3, eq. 5.3-5.4: the light-map octree of one model's samples: leaves at `depth` in the
/// cells holding a sample and their neighbours; a leaf's normal is the mean normal of the samples
/// in it (else within g of its centre); each corner holds sum y_i E_i / sum y_i over the samples
/// within g whose normals pass the test, y_i = (1 - |q - p_i| / g)^2. A corner with no such
/// sample takes the mean of the leaf's other corners; a leaf with none is left out.
gi::GiOctree build_light_map_octree(std::span<const Sample> samples, const double root_min[3],
                                    double root_size, const GatherOptions& options);

}  // namespace prt::lightmap
