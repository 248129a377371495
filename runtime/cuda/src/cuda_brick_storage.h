// PointRT CUDA: streamed bricks' storage on the GPU (cuda_brick_storage.cpp), for the CUDA backend.
#pragma once

#include <cstdint>
#include <memory>

#include "prt/cuda/device_scene.h"
#include "prt/runtime/brick_stream.h"

namespace prt::cuda {

/// Device storage of model `model`'s streamed bricks (rt::BrickStream): an arena of `arena.bytes`
/// and the per-brick tables on the device, set into `scene`'s device model (DeviceScene::
/// set_model_bricks). `scene` must hold the scene uploaded with the model's bricks streamed.
std::unique_ptr<rt::BrickStorage> make_cuda_brick_storage(DeviceScene& scene, std::uint32_t model,
                                                          const rt::BrickArena& arena);

/// The default memory budget (--gpu-budget): the device's free memory minus 512 MiB.
std::uint64_t default_memory_budget();

}  // namespace prt::cuda
