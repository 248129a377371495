// PointRT prt-photons (thesis 5.4): photon shooting over a scene (CPU threads or CUDA) and the
// caustic octree built from the deposits (photon gathering, thesis 5.4.2).
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <span>
#include <string>
#include <vector>

#include "gi_build.h"
#include "prt/core/photon.h"
#include "prt/core/scene_view.h"

namespace prt::photons {

// The device-callable photon tracing lives in the core (prt/core/photon.h), for the CPU path here
// and the CUDA backend alike; these names keep prt-photons' code readable.
using core::emit_photon;
using core::hash64;
using core::PhotonDeposit;
using core::photons_per_light;
using core::PhotonTally;
using core::PhotonTallyF;
using core::trace_photon;
using core::unit_float;
using ShootParams = core::PhotonShootParams;

using gi::CellBins;
using gi::GiOctree;
using gi::KeyMap;
using gi::LeafValues;

struct ShootOptions {
    ShootParams params;
    std::string backend = "auto";  ///< auto | cpu | cuda
    unsigned threads = 0;          ///< CPU workers (0 = every core the process may use)
};

struct ShootResult {
    std::vector<PhotonDeposit> deposits;  ///< every model's; CPU: in photon order, whatever the threads
    PhotonTally tally;
    double seconds = 0;         ///< shooting, wall clock (GPU: upload, kernels and deposit download)
    double kernel_seconds = 0;  ///< GPU: the shooting kernels alone (CUDA events); CPU: = seconds
    double setup_seconds = 0;   ///< GPU: the device's first use and the scene's upload, within `seconds`
    std::string backend;        ///< "cpu (N threads)" or the GPU's name
};

/// The factor that makes a cube face's pixel-centre solid angles sum to exactly 4 pi / 6 (double).
float solid_angle_norm(std::uint32_t face_res);

/// "cpu" or "cuda" for a requested backend ("auto": CUDA when a device is usable); `why` says why
/// auto fell back to the CPU. Throws prt::Error when "cuda" is asked for and unusable.
std::string resolve_backend(const std::string& requested, std::string* why = nullptr);

/// Starts creating the GPU's context on a thread when `backend` (resolved: "cpu" or "cuda") is
/// "cuda", so the bakes pay it while they load the scene (issue 20: it was 0.13 s of the 0.14 s a
/// default prt-photons run spent shooting on the H100); wait() on the result before the GPU path.
std::future<void> warm_up(const std::string& backend);

/// thesis 5.4.1: shoots photons_per_light() photons from every light of `scene` (a host view; the
/// CUDA path uploads it). `progress(done, total)` is called from the calling thread.
ShootResult shoot_photons(const core::SceneView& scene, const ShootOptions& options,
                          const std::function<void(std::uint64_t, std::uint64_t)>& progress = {});

/// Options of the caustic octree (thesis 5.4.2).
struct GatherOptions {
    std::uint32_t depth = 10;    ///< leaf level of the caustic octree
    float radius_edges = 1.0f;   ///< gather radius g, in caustic leaf edges
    float render_scale = 1.0f;   ///< the model's scale in the scene (irradiance per scene area)
    float cos_threshold = 0.0f;  ///< lookup normal test (GiInfo::cos_threshold)
    unsigned threads = 0;
    /// When set: seconds spent binning the deposits, listing the blocks, on the corners' densities
    /// and the leaves (one pass per block), encoding the leaves, building the nodes.
    double* phase_seconds = nullptr;  ///< 5 doubles
};

/// thesis 5.4.2 + eq. 5.1-5.2: the caustic octree of one model from its deposits (local frame):
/// leaves at `depth` wherever a deposit lies within g of one of their corners; each corner holds
/// the density estimate E(q) = sum 2 / (pi g^2) (1 - |q - p|^2 / g^2) flux over the deposits
/// within g (g in scene units, so E is irradiance in the scene's units); each leaf the
/// flux-weighted mean deposit normal (zero when the deposits came from both sides). Parallel over
/// `threads` workers; the tree is byte-identical whatever their number.
GiOctree build_caustic_octree(std::span<const PhotonDeposit> deposits, const double root_min[3],
                              double root_size, const GatherOptions& options);

}  // namespace prt::photons
