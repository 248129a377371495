// PointRT runtime (host): what every backend (cpu, cuda, hybrid) implements: upload a scene once,
// render frames of it. Backends run the same core functions (prt/core/render.h).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "prt/core/camera.h"
#include "prt/core/scene_view.h"
#include "prt/runtime/image.h"

namespace prt::core {
struct RayCounters;
struct BrickView;
struct CastRays;
struct CastOutputs;
}  // namespace prt::core

namespace prt::rt {

class BrickStorage;
struct BrickArena;

/// Counters and timings of one rendered frame.
struct FrameStats {
    double seconds = 0;    ///< wall time of render() (host clock)
    double device_ms = 0;  ///< GPU time from CUDA events (0 for the CPU backend)
    std::uint64_t pixels = 0;
    std::uint64_t primary = 0, secondary = 0, shadow = 0;
    std::uint64_t leaves = 0, splat_tests = 0;
    std::uint64_t truncated = 0, sanitized = 0, dropped = 0;
    std::uint64_t culled = 0;     ///< filled leaves passed unread by their bounds (core LeafBounds)
    std::uint64_t fallbacks = 0;  ///< rays that fell back to a brick's LOD disc (core bricks.h, render.h)
    double gpu_share = 0;         ///< hybrid: fraction of rows the GPU rendered
    /// CUDA megakernel: 32-pixel items handed out first, as the previous frame's heavy ones
    /// (BackendOptions::cuda_heavy_first)
    std::uint64_t heavy_first = 0;

    std::uint64_t rays() const { return primary + secondary + shadow; }
    FrameStats& operator+=(const FrameStats& o);
    /// Adds a thread's or a tile's ray counters (core::RayCounters, render.h).
    FrameStats& operator+=(const core::RayCounters& c);
};

/// One frame request: a camera in the render frame, settings, an image size and the rows to
/// render ([row_begin, row_end); the hybrid backend splits frames by rows).
struct FrameRequest {
    core::PinholeCamera camera;
    core::RenderParams params;
    std::uint32_t width = 0, height = 0;
    std::uint32_t row_begin = 0, row_end = 0;  ///< row_end 0 means height
    bool download = true;  ///< GPU backends: copy the frame into `image` (benchmarks skip it)
    /// CUDA backend only: a device pointer (e.g. a mapped OpenGL pixel buffer, prt/cuda/gl_interop.h)
    /// that receives the display-encoded frame, width * height RGBA8 words, row 0 at the top,
    /// instead of the backend's own buffer; `image.rgba8` is then not written. Other backends
    /// ignore it (the window passes it to the CUDA backend only).
    void* device_rgba8 = nullptr;
};

/// Where a ray batch's arrays live (Backend::cast): host memory, or device memory of the CUDA
/// backend's GPU (no copies; the CPU backend refuses it).
enum class Memory { host, device };

/// Statistics of one Backend::cast() or Backend::occluded() batch.
struct CastStats {
    double seconds = 0;    ///< wall time of the call (host clock), copies included
    double device_ms = 0;  ///< GPU time of the kernel (0 for the CPU backend)
    std::uint64_t rays = 0;
    std::uint64_t leaves = 0, splat_tests = 0;  ///< CPU backend only (the kernels keep no counters)
};

/// Load statistics of set_scene().
struct UploadStats {
    std::uint64_t bytes = 0;
    double seconds = 0;
    double gb_per_s() const { return seconds > 0 ? static_cast<double>(bytes) / seconds * 1e-9 : 0.0; }
};

class Backend {
public:
    virtual ~Backend() = default;
    /// "cpu", "cuda" or "hybrid".
    virtual std::string name() const = 0;
    /// A one-line description of the device (CPU threads, GPU name).
    virtual std::string device() const = 0;
    /// Makes the scene current. The views' arrays must stay valid until the next set_scene() or
    /// the backend's destruction (the CPU backend reads them in place; the CUDA backend copies).
    virtual UploadStats set_scene(const core::SceneView& scene) = 0;
    /// Renders the requested rows into `image` (already sized width x height).
    virtual FrameStats render(const FrameRequest& request, Image& image) = 0;
    /// Casts a batch of the caller's rays (prt/core/cast.h: world-frame arrays, t in [t_min, t_max))
    /// against the current scene: closest hits over every surface, answers into `out`. `memory`
    /// says where all the arrays live: device memory only on the CUDA backend (others throw
    /// prt::Error); host arrays are copied to the GPU and back by the CUDA backend. The default
    /// throws prt::Error (a backend without ray casting).
    virtual CastStats cast(const core::CastRays& rays, const core::CastOutputs& out,
                           Memory memory = Memory::host);
    /// Occlusion (any hit in [t_min, t_max)) of a batch: flags[i] 1 when blocked; `valid` (optional)
    /// 0 for invalid rays (cast.h), whose flag is 0.
    virtual CastStats occluded(const core::CastRays& rays, std::uint8_t* flags, std::uint8_t* valid,
                               Memory memory = Memory::host);
    /// Streamed bricks (brick_stream.h): after set_scene(), this backend's storage for model m's
    /// bricks (`host`: the model's host brick view). Null (the default): the backend reads the host
    /// views in place, so host storage serves (CPU).
    virtual std::unique_ptr<BrickStorage> make_brick_storage(std::uint32_t model, const core::BrickView& host,
                                                             const BrickArena& arena);
    /// The memory budget --gpu-budget defaults to: the device's free memory minus a margin; 0
    /// (the default): unlimited, the scene is read in place from the mapped pools (CPU).
    virtual std::uint64_t default_memory_budget() const { return 0; }
    /// Whether bricks can be streamed on this backend (hybrid: no, it loads in core).
    virtual bool can_stream() const { return true; }
};

/// Which backends this build has and this machine can run.
struct BackendAvailability {
    bool cpu = true;
    bool cuda_built = false;
    bool cuda_device = false;
    std::string cuda_why;  ///< one line: why CUDA cannot be used
};
BackendAvailability backend_availability();

/// Backend options.
struct BackendOptions {
    unsigned cpu_threads = 0;     ///< 0: every core the process may use
    bool cuda_wavefront = false;  ///< several kernels per frame (thesis 2.4) instead of one
    /// megakernel: persistent warps taking 32-pixel items from a queue (Aila-Laine) instead of one
    /// item per warp from the block index
    bool cuda_persistent = true;
    /// persistent megakernel: hand out first the items that were heavy in the previous frame of the
    /// same shape (cuda_backend.cu, ItemOrder), instead of image order alone
    bool cuda_heavy_first = true;
    bool cuda_linear_mapping = false;  ///< rays to threads row by row instead of in Z-order (thesis 2.3)
    /// megakernel occupancy hint: 256-thread blocks per SM, 1-6 (0: each kernel's default: splats,
    /// bricked splats and ISO 3, patches and MLS 2, the general kernel 4)
    int cuda_min_blocks = 0;
    bool cuda_max_l1 = true;  ///< prefer L1 over shared memory for the megakernel
    /// ISO megakernels on a scene with macro-regions: "auto" (the first frames of each kind time the
    /// walk with its regions and the walk compiled without them, core::k_mask_plain_walk, and keep
    /// the faster, checking the other now and then), "regions" or "plain". Without regions the plain
    /// walk always runs (the same leaves, less code).
    std::string cuda_iso_walk = "auto";
};

/// Creates a backend by name: "cpu", "cuda", "hybrid" or "auto" (cuda when a device exists, else
/// cpu). Throws prt::Error with one clear line when the backend cannot run here.
std::unique_ptr<Backend> make_backend(const std::string& name, const BackendOptions& options = {});

}  // namespace prt::rt
