#include "prt/cpu/cpu_backend.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "prt/core/cast.h"
#include "prt/core/render.h"
#include "prt/error.h"
#include "prt/parallel.h"

namespace prt::cpu {

namespace {

constexpr std::uint32_t k_tile = 16;

class CpuBackend final : public rt::Backend {
public:
    explicit CpuBackend(unsigned threads) : m_threads(resolve_threads(threads)) {}

    std::string name() const override { return "cpu"; }
    std::string device() const override { return "CPU, " + std::to_string(m_threads) + " threads"; }

    rt::UploadStats set_scene(const core::SceneView& scene) override {
        m_scene = scene;
        return {};
    }

    rt::FrameStats render(const rt::FrameRequest& req, rt::Image& image) override {
        const auto start = std::chrono::steady_clock::now();
        const std::uint32_t w = req.width, h = req.height;
        const std::uint32_t y0 = std::min(req.row_begin, h);
        const std::uint32_t y1 = req.row_end == 0 ? h : std::min(req.row_end, h);
        if (image.width != w || image.height != h) image.resize(w, h);
        core::SceneView scene = m_scene;
        scene.params = req.params;
        core::set_lod_cone(scene.params, req.camera, req.height);
        const std::uint32_t tiles_x = (w + k_tile - 1) / k_tile;
        const std::uint32_t tiles_y = y1 > y0 ? (y1 - y0 + k_tile - 1) / k_tile : 0;
        const std::uint32_t tiles = tiles_x * tiles_y;
        std::vector<rt::FrameStats> totals(m_threads);
        parallel_chunks(tiles, 1, m_threads, [&](std::size_t first, std::size_t last, unsigned worker) {
            rt::FrameStats& total = totals[worker];
            for (auto t = static_cast<std::uint32_t>(first); t < last; ++t) {
                const std::uint32_t tx = (t % tiles_x) * k_tile, ty = y0 + (t / tiles_x) * k_tile;
                const std::uint32_t xe = std::min(tx + k_tile, w), ye = std::min(ty + k_tile, y1);
                core::RayCounters c;  // per tile: the 32-bit counters never wrap
                for (std::uint32_t y = ty; y < ye; ++y) {
                    for (std::uint32_t x = tx; x < xe; ++x) {
                        const core::Vec3 color = core::render_pixel(scene, req.camera, x, y, w, h, c);
                        const std::size_t i = static_cast<std::size_t>(y) * w + x;
                        image.rgb[i * 3 + 0] = color.x;
                        image.rgb[i * 3 + 1] = color.y;
                        image.rgb[i * 3 + 2] = color.z;
                        image.rgba8[i] = core::pack_rgba8(core::encode_display(color, scene.params));
                    }
                }
                total += c;
            }
        });
        rt::FrameStats stats;
        for (const rt::FrameStats& s : totals) stats += s;
        stats.pixels = static_cast<std::uint64_t>(w) * (y1 - y0);
        stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return stats;
    }

    // Ray batches (issue 18): the core's cast_one / occluded_one over all threads, 1024 rays a chunk.
    rt::CastStats cast(const core::CastRays& rays, const core::CastOutputs& out, rt::Memory memory) override {
        return run_batch(rays, memory, [&](std::size_t i, core::RayCounters& c) {
            core::cast_one(m_scene, rays, out, i, c);
        });
    }
    rt::CastStats occluded(const core::CastRays& rays, std::uint8_t* flags, std::uint8_t* valid,
                           rt::Memory memory) override {
        return run_batch(rays, memory, [&](std::size_t i, core::RayCounters& c) {
            core::occluded_one(m_scene, rays, flags, valid, i, c);
        });
    }

private:
    template <class One>
    rt::CastStats run_batch(const core::CastRays& rays, rt::Memory memory, One&& one) {
        if (memory != rt::Memory::host)
            throw Error("the cpu backend reads host memory only: device arrays need the cuda backend");
        const auto start = std::chrono::steady_clock::now();
        std::vector<rt::FrameStats> totals(m_threads);
        constexpr std::size_t k_chunk = 1024;
        parallel_chunks(rays.count, k_chunk, m_threads,
                        [&](std::size_t first, std::size_t last, unsigned worker) {
                            core::RayCounters c;  // per chunk: the 32-bit counters never wrap
                            for (std::size_t i = first; i < last; ++i) one(i, c);
                            totals[worker] += c;
                        });
        rt::FrameStats sum;
        for (const rt::FrameStats& s : totals) sum += s;
        rt::CastStats stats;
        stats.rays = rays.count;
        stats.leaves = sum.leaves;
        stats.splat_tests = sum.splat_tests;
        stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return stats;
    }

    unsigned m_threads;
    core::SceneView m_scene;
};

}  // namespace

std::unique_ptr<rt::Backend> make_cpu_backend(unsigned threads) {
    return std::make_unique<CpuBackend>(threads);
}

}  // namespace prt::cpu
