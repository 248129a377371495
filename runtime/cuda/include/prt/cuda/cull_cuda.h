// PointRT CUDA: prt-cull's GPU path (thesis 3.4): the per-leaf probe-ray culling and the hole-rate
// rays of preprocess/splat/cull_build.h, run in kernels over the same functions the CPU path runs. Plain
// C++ header (no CUDA types), so cull_build.cpp, compiled by g++, calls it. Implemented in
// runtime/cuda/src/cull.cu; built only with nvcc (target prt_cull_cuda).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "prt/core/cull.h"

namespace prt::cuda {

/// Whether a CUDA device can be used here. On false, `why` (if given) gets one line saying why.
/// Never throws.
bool cull_device_available(std::string* why = nullptr);

/// Name of device 0, or "" when none.
std::string cull_device_name();

/// Runs pre::cull_leaf() for every filled leaf of `view` on device 0. `view` points at host
/// memory: its arrays are uploaded, `keep` (one flag per stored splat, initialised as cull_leaf()
/// expects) is uploaded and the result downloaded into it. `progress(done, leaves)` is called
/// from the calling thread between launches. Throws prt::Error on any CUDA error.
core::CullCounters cull_leaves_cuda(const core::CullView& view, std::span<std::uint8_t> keep,
                                   const std::function<void(std::uint64_t, std::uint64_t)>& progress);

/// Traces every ray through both octrees (pre::trace_hole_ray()) on device 0; `full` and `culled`
/// point at host memory. `out` has one sample per ray.
void trace_hole_rays_cuda(const core::OctreeView& full, const core::OctreeView& culled,
                          std::span<const core::HoleRay> rays, const core::BlendOptions& blend,
                          std::uint32_t max_steps, std::span<core::HoleSample> out);

}  // namespace prt::cuda
