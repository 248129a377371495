// PointRT CUDA backend: the core's functions (prt/core/render.h) in kernels. Plain C++ header: no
// CUDA types, so host code compiled by g++ (the player, tests) can include it.
#pragma once

#include <memory>
#include <string>

#include "prt/cuda/device.h"
#include "prt/runtime/backend.h"

namespace prt::cuda {

/// Creates the CUDA backend on device 0. Throws prt::Error with one line when no device is usable.
std::unique_ptr<rt::Backend> make_cuda_backend(const rt::BackendOptions& options = {});

}  // namespace prt::cuda
