// PointRT CUDA: whether a device can be used here, and its name. One answer for the backend and
// the preprocessing tools' GPU paths (prt-cull, prt-photons). Plain C++ header: no CUDA types.
// Implemented in runtime/cuda/src/device.cpp (target prt_cuda_device).
#pragma once

#include <string>

namespace prt::cuda {

/// Whether a CUDA device can be used here. On false, `why` (if given) gets one line saying why
/// (no driver, no device, ...). Never throws.
bool device_available(std::string* why = nullptr);

/// Name of device 0 ("NVIDIA H100 80GB HBM3"), or "" when none.
std::string device_name();

/// Creates device 0's primary context now (a process's first CUDA use: about 0.13 s on the H100),
/// so a tool can pay it on a thread while it loads its input; every thread shares that context.
/// Never throws (errors surface at the next real use).
void warm_up_device();

/// Destroys device 0's primary context (cudaDeviceReset) once a tool is done with the GPU, so
/// that most of the driver's teardown, which a process otherwise pays at exit (about 0.1 s on the
/// H200 host), can run on a thread while the tool writes its output. No CUDA object of the process
/// may be alive or in use then. Never throws.
void release_device();

}  // namespace prt::cuda
