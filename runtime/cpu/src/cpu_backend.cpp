#include "prt/cpu/cpu_backend.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "prt/core/render.h"

namespace prt::cpu {

namespace {

constexpr std::uint32_t k_tile = 16;

/// A fixed set of worker threads that run one job at a time; the calling thread joins in.
class ThreadPool {
public:
    explicit ThreadPool(unsigned threads) {
        m_size = threads > 0 ? threads : std::max(1u, std::thread::hardware_concurrency());
        for (unsigned i = 1; i < m_size; ++i) m_workers.emplace_back([this, i] { loop(i); });
    }
    ~ThreadPool() {
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            m_stop = true;
        }
        m_wake.notify_all();
        for (std::thread& t : m_workers) t.join();
    }
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    unsigned size() const { return m_size; }

    /// Runs job(worker_index) on every worker and on the caller (index 0); returns when all are done.
    void run(const std::function<void(unsigned)>& job) {
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            m_job = &job;
            m_pending = static_cast<unsigned>(m_workers.size());
            ++m_generation;
        }
        m_wake.notify_all();
        job(0);
        std::unique_lock<std::mutex> lock(m_mutex);
        m_done.wait(lock, [this] { return m_pending == 0; });
        m_job = nullptr;
    }

private:
    void loop(unsigned index) {
        std::uint64_t seen = 0;
        for (;;) {
            const std::function<void(unsigned)>* job;
            {
                std::unique_lock<std::mutex> lock(m_mutex);
                m_wake.wait(lock, [&] { return m_stop || m_generation != seen; });
                if (m_stop) return;
                seen = m_generation;
                job = m_job;
            }
            (*job)(index);
            {
                std::lock_guard<std::mutex> lock(m_mutex);
                if (--m_pending == 0) m_done.notify_one();
            }
        }
    }

    std::vector<std::thread> m_workers;
    unsigned m_size = 1;
    std::mutex m_mutex;
    std::condition_variable m_wake, m_done;
    const std::function<void(unsigned)>* m_job = nullptr;
    unsigned m_pending = 0;
    std::uint64_t m_generation = 0;
    bool m_stop = false;
};

class CpuBackend final : public rt::Backend {
public:
    explicit CpuBackend(unsigned threads) : m_pool(threads) {}

    std::string name() const override { return "cpu"; }
    std::string device() const override { return "CPU, " + std::to_string(m_pool.size()) + " threads"; }

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
        const std::uint32_t tiles_x = (w + k_tile - 1) / k_tile;
        const std::uint32_t tiles_y = y1 > y0 ? (y1 - y0 + k_tile - 1) / k_tile : 0;
        const std::uint32_t tiles = tiles_x * tiles_y;
        std::atomic<std::uint32_t> next{0};
        std::vector<rt::FrameStats> totals(m_pool.size());
        const std::function<void(unsigned)> job = [&](unsigned worker) {
            rt::FrameStats& total = totals[worker];
            for (;;) {
                const std::uint32_t t = next.fetch_add(1, std::memory_order_relaxed);
                if (t >= tiles) break;
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
        };
        m_pool.run(job);
        rt::FrameStats stats;
        for (const rt::FrameStats& s : totals) stats += s;
        stats.pixels = static_cast<std::uint64_t>(w) * (y1 - y0);
        stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return stats;
    }

private:
    ThreadPool m_pool;
    core::SceneView m_scene;
};

}  // namespace

std::unique_ptr<rt::Backend> make_cpu_backend(unsigned threads) {
    return std::make_unique<CpuBackend>(threads);
}

}  // namespace prt::cpu
