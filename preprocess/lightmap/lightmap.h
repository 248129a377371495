// PointRT prt-lightmap (thesis 5.3): a diffuse light map per model: surface samples (the model's
// own points, or points sampled on its patches, a few per light-map leaf; issue 20: on whatever
// surface the model is traced as) whose indirect irradiance is path traced over the scene
// (lightmap_trace.h), gathered at the corners of a light-map octree with the weighted average of
// eq. 5.3-5.4 and rejection of samples whose normals disagree with the leaf's.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "gi_build.h"
#include "gi_frame.h"
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
    std::uint32_t model = 0;  ///< index into the scene's models
    /// Issue 20: > 0 for models traced as ISO, MLS or patches: the sample is first moved onto the
    /// traced surface by a probe ray reaching this far (render frame) on either side
    /// (core::settle_sample); its position and normal become the hit's.
    float settle_reach = 0.0f;
    bool settled = true;  ///< false: the probe found no surface of the model (the sample is dropped)
};

/// Picks at most `per_leaf` of the surface points in every cell at `depth` (evenly spread over the
/// cell's points in their order) as samples of model `model_index`; `model` places them in the
/// render frame. `settle_reach` (local units; 0 for splats): see Sample::settle_reach.
std::vector<Sample> select_samples(const gi::SurfacePoints& points, std::uint32_t model_index,
                                   const core::ModelView& model, const double root_min[3], double root_size,
                                   std::uint32_t depth, std::uint32_t per_leaf, float settle_reach = 0.0f);

/// How far a model's samples are probed for its traced surface: 0 for splats (their points lie on
/// their splats), else one light-map cell edge for scan points (ISO, MLS), a hundredth of it for
/// points sampled on the patches themselves.
float settle_reach(core::SurfaceKind surface, const gi::SurfacePoints& points, double cell_edge);

/// Where and how fast the samples were traced.
struct TraceReport {
    std::string backend;        ///< "cpu (N threads)" or the GPU's name
    double kernel_seconds = 0;  ///< GPU: the kernels' time; CPU: the tracing time
};

/// Traces every sample's indirect irradiance (core::trace_light_map_sample), settling those with a
/// settle_reach first, on `backend` ("cpu", "cuda", or "auto": the GPU when there is one; the
/// resolved name, photons::resolve_backend) with `threads` CPU workers. `progress(done)` from the
/// calling thread.
TraceReport trace_samples(const core::SceneView& scene, const TraceParams& params, std::span<Sample> samples,
                          std::uint64_t first_index, unsigned threads,
                          const std::function<void(std::uint64_t)>& progress = {},
                          const std::string& backend = "cpu");

/// Removes the samples that did not settle; returns how many went.
std::size_t drop_unsettled(std::vector<Sample>& samples);

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
