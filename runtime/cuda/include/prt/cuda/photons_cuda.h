// PointRT CUDA: prt-photons' GPU path (thesis 5.4.1: "photon shooting is done in parallel, on the
// GPU"): one thread per photon over photons::trace_photon(), the function the CPU path runs, on a
// device copy of the scene (DeviceScene). Plain C++ header (no CUDA types), so photons.cpp,
// compiled by g++, calls it. Implemented in runtime/cuda/src/photons.cu (target prt_photons_cuda).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "prt/core/photon.h"
#include "prt/core/scene_view.h"

namespace prt::cuda {

/// Whether a CUDA device can be used here. On false, `why` (if given) gets one line saying why.
/// Never throws.
bool photons_device_available(std::string* why = nullptr);

struct PhotonsCudaResult {
    std::vector<core::PhotonDeposit> deposits;
    core::PhotonTally tally;
    std::string device;         ///< the GPU's name
    double kernel_seconds = 0;  ///< sum of the shooting kernels' times (CUDA events)
    double setup_seconds = 0;   ///< the device's first use (context) and the scene's upload (wall clock)
};

/// Shoots photons_per_light(params) photons from every light of `host` (host pointers: the scene
/// is uploaded, then freed) on device 0; deposits come back in no particular order.
/// `progress(done, total)` is called from the calling thread between launches. Throws prt::Error
/// on any CUDA error.
PhotonsCudaResult shoot_photons_cuda(const core::SceneView& host, const core::PhotonShootParams& params,
                                     const std::function<void(std::uint64_t, std::uint64_t)>& progress);

}  // namespace prt::cuda
