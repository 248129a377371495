// PointRT CUDA: prt-lightmap's GPU path (thesis 5.3, issue 20: "the light map on the GPU, through
// the same core"): one thread per light-map sample over core::trace_light_map_sample(), the
// function the CPU path runs, on a device copy of the scene (DeviceScene). Plain C++ header (no
// CUDA types), so lightmap.cpp, compiled by g++, calls it. Implemented in
// runtime/cuda/src/lightmap.cu (target prt_photons_cuda, which both bakes link).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "prt/core/lightmap.h"
#include "prt/core/scene_view.h"

namespace prt::cuda {

struct LightMapCudaResult {
    std::string device;         ///< the GPU's name
    double kernel_seconds = 0;  ///< sum of the tracing kernels' times (CUDA events)
};

/// Traces every sample (sample k has index first_index + k, as on the CPU) into `out` (same size as
/// `in`) on device 0; `host` holds host pointers (the scene is uploaded, then freed).
/// `progress(done)` is called from the calling thread between launches. Throws prt::Error on any
/// CUDA error.
LightMapCudaResult trace_light_map_cuda(const core::SceneView& host, const core::LightMapTraceParams& params,
                                        std::span<const core::LightMapSampleIn> in, std::uint64_t first_index,
                                        std::span<core::LightMapSampleOut> out,
                                        const std::function<void(std::uint64_t)>& progress);

}  // namespace prt::cuda
