// PointRT CUDA backend: the core's functions (prt/core/render.h) in kernels. Plain C++ header: no
// CUDA types, so host code compiled by g++ (the player, tests) can include it.
#pragma once

#include <memory>
#include <string>

#include "prt/runtime/backend.h"

namespace prt::cuda {

/// Whether a CUDA device can be used here. On false, `why` (if given) gets one line saying why
/// (no driver, no device, ...). Never throws.
bool device_available(std::string* why = nullptr);

/// Name of device 0 ("NVIDIA H100 80GB HBM3"), or "" when none.
std::string device_name();

/// Creates the CUDA backend on device 0. Throws prt::Error with one line when no device is usable.
std::unique_ptr<rt::Backend> make_cuda_backend(const rt::BackendOptions& options = {});

}  // namespace prt::cuda
