// PointRT CUDA backend: the ray-batch kernels' host entries (cast.cu), called by the backend
// (cuda_backend.cu) on its device scene and stream. Host-only header.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "device_buffer.h"
#include "prt/core/scene_view.h"
#include "prt/runtime/backend.h"

namespace prt::cuda {

/// Device copies of a host batch's inputs and outputs, kept by the backend between batches (they
/// only grow), so repeated batches do not allocate.
struct CastStaging {
    DeviceBuffer<unsigned char> origins, directions, t_min, t_max;
    DeviceBuffer<std::uint8_t> hit, valid;
    DeviceBuffer<float> t, position, normal, color;
    DeviceBuffer<std::int32_t> model;
    DeviceBuffer<std::int64_t> element;
};

/// What a batch runs on: the backend's device scene, its surfaces (core::scene_mask), its stream
/// and timing events.
struct CastContext {
    core::SceneView scene;
    std::uint32_t surface_mask = 0;
    cudaStream_t stream = nullptr;
    cudaEvent_t start = nullptr, stop = nullptr;
    CastStaging* staging = nullptr;  ///< the backend's (host batches)
};

/// Closest hits of a batch (Backend::cast); host arrays are staged through device copies.
rt::CastStats cast_batch(const CastContext& ctx, const core::CastRays& rays, const core::CastOutputs& out,
                         rt::Memory memory);
/// Occlusion of a batch (Backend::occluded).
rt::CastStats occluded_batch(const CastContext& ctx, const core::CastRays& rays, std::uint8_t* flags,
                             std::uint8_t* valid, rt::Memory memory);

}  // namespace prt::cuda
