// PointRT: the backend factory (cpu / cuda / hybrid / auto) and the hybrid backend.
#include <algorithm>
#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <utility>

#include "prt/cpu/cpu_backend.h"
#include "prt/error.h"
#include "prt/runtime/backend.h"
#ifdef PRT_HAVE_CUDA
#include "prt/cuda/cuda_backend.h"
#endif

namespace prt::rt {

namespace {

/// --backend auto where CUDA cannot run: the CPU backend, whose device() also says why the GPU
/// was not used (issue 10: the fallback gives one note, the tools' backend line, not silence and
/// not a stack of messages; --quiet silences it with the rest).
class AutoFallbackBackend final : public Backend {
public:
    AutoFallbackBackend(std::unique_ptr<Backend> cpu, std::string why)
        : m_cpu(std::move(cpu)), m_why(std::move(why)) {}

    std::string name() const override { return m_cpu->name(); }
    std::string device() const override { return m_cpu->device() + " (--backend auto: " + m_why + ")"; }
    UploadStats set_scene(const core::SceneView& scene) override { return m_cpu->set_scene(scene); }
    FrameStats render(const FrameRequest& req, Image& image) override { return m_cpu->render(req, image); }
    CastStats cast(const core::CastRays& rays, const core::CastOutputs& out, Memory memory) override {
        return m_cpu->cast(rays, out, memory);
    }
    CastStats occluded(const core::CastRays& rays, std::uint8_t* flags, std::uint8_t* valid,
                       Memory memory) override {
        return m_cpu->occluded(rays, flags, valid, memory);
    }

private:
    std::unique_ptr<Backend> m_cpu;
    std::string m_why;
};

#ifdef PRT_HAVE_CUDA
/// seed 002 (hybrid CPU+GPU): each frame's rows are split between the GPU and the CPU in
/// proportion to their measured speeds (pixels per second over the previous frame, smoothed), so
/// both finish at about the same time. The GPU renders the top rows, the CPU the rest, at once.
class HybridBackend final : public Backend {
public:
    HybridBackend(std::unique_ptr<Backend> gpu, std::unique_ptr<Backend> cpu)
        : m_gpu(std::move(gpu)), m_cpu(std::move(cpu)) {}

    std::string name() const override { return "hybrid"; }
    std::string device() const override { return m_gpu->device() + " + " + m_cpu->device(); }

    UploadStats set_scene(const core::SceneView& scene) override {
        m_cpu->set_scene(scene);
        return m_gpu->set_scene(scene);
    }
    // Ray batches go to the GPU (the caller's arrays may be device memory).
    CastStats cast(const core::CastRays& rays, const core::CastOutputs& out, Memory memory) override {
        return m_gpu->cast(rays, out, memory);
    }
    CastStats occluded(const core::CastRays& rays, std::uint8_t* flags, std::uint8_t* valid,
                       Memory memory) override {
        return m_gpu->occluded(rays, flags, valid, memory);
    }
    // Both sides read the same bricks: the hybrid backend loads them in core.
    bool can_stream() const override { return false; }
    std::uint64_t default_memory_budget() const override { return m_gpu->default_memory_budget(); }

    FrameStats render(const FrameRequest& req, Image& image) override {
        const auto start = std::chrono::steady_clock::now();
        const std::uint32_t h = req.height;
        const std::uint32_t y0 = std::min(req.row_begin, h);
        const std::uint32_t y1 = req.row_end == 0 ? h : std::min(req.row_end, h);
        if (image.width != req.width || image.height != h) image.resize(req.width, h);
        const std::uint32_t rows = y1 - y0;
        std::uint32_t gpu_rows = static_cast<std::uint32_t>(std::clamp(m_share, 0.0, 1.0) * rows + 0.5);
        gpu_rows = std::min(gpu_rows, rows);
        const std::uint32_t split = y0 + gpu_rows;
        FrameRequest greq = req, creq = req;
        greq.row_begin = y0;
        greq.row_end = split;
        creq.row_begin = split;
        creq.row_end = y1;
        FrameStats gs, cs;
        // Both write disjoint rows of the same image.
        auto gpu_job = std::async(std::launch::async,
                                  [&] { return gpu_rows ? m_gpu->render(greq, image) : FrameStats{}; });
        if (split < y1) cs = m_cpu->render(creq, image);
        gs = gpu_job.get();
        // Speeds in pixels per second; a side that rendered nothing keeps its previous estimate.
        if (gs.pixels && gs.seconds > 0) m_gpu_speed = gs.pixels / gs.seconds;
        if (cs.pixels && cs.seconds > 0) m_cpu_speed = cs.pixels / cs.seconds;
        const double target = m_gpu_speed / (m_gpu_speed + m_cpu_speed);
        // The first measured frame sets the split; later frames smooth it (speeds vary with the view).
        m_share = m_measured ? 0.5 * m_share + 0.5 * target : target;
        m_measured = m_measured || (gs.pixels && cs.pixels);
        // Keep at least one row on each side so both speeds stay measured.
        if (rows > 1) m_share = std::clamp(m_share, 1.0 / rows, 1.0 - 1.0 / rows);
        FrameStats s = gs;
        s += cs;
        s.device_ms = gs.device_ms;
        s.gpu_share = rows ? static_cast<double>(gpu_rows) / rows : 0.0;
        s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return s;
    }

private:
    std::unique_ptr<Backend> m_gpu, m_cpu;
    double m_share = 0.95;  // first guess, until both sides were measured once
    double m_gpu_speed = 19.0, m_cpu_speed = 1.0;
    bool m_measured = false;
};
#endif

}  // namespace

BackendAvailability backend_availability() {
    BackendAvailability a;
#ifdef PRT_HAVE_CUDA
    a.cuda_built = true;
    a.cuda_device = cuda::device_available(&a.cuda_why);
#else
    a.cuda_why = "this build has no CUDA backend (configured without nvcc or with PRT_WITH_CUDA=OFF)";
#endif
    return a;
}

std::unique_ptr<Backend> make_backend(const std::string& name, const BackendOptions& options) {
    if (name == "cpu") return cpu::make_cpu_backend(options.cpu_threads);
    if (name == "cuda" || name == "hybrid" || name == "auto") {
        const BackendAvailability a = backend_availability();
        if (!a.cuda_device) {
            if (name == "auto")
                return std::make_unique<AutoFallbackBackend>(cpu::make_cpu_backend(options.cpu_threads),
                                                             a.cuda_why);
            throw Error("--backend " + name + ": " + a.cuda_why + " (use --backend cpu)");
        }
#ifdef PRT_HAVE_CUDA
        if (name == "hybrid") {
            return std::make_unique<HybridBackend>(cuda::make_cuda_backend(options),
                                                   cpu::make_cpu_backend(options.cpu_threads));
        }
        return cuda::make_cuda_backend(options);
#endif
    }
    throw Error("unknown backend '" + name + "' (expected cpu, cuda, hybrid or auto)");
}

}  // namespace prt::rt
