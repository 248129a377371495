#include "ray_profile.h"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <mutex>
#include <thread>

#include "prt/core/render.h"
#include "prt/parallel.h"

namespace prt::player {

namespace {

constexpr std::uint32_t k_warp_w = 8, k_warp_h = 4;  // thesis 2.3: a warp's Z-order block

/// Work of one pixel's rays by depth (index k_max_bounces + 1: its shadow rays).
struct PixelWork {
    std::uint32_t leaves[core::k_max_bounces + 2] = {};
    std::uint32_t tests[core::k_max_bounces + 2] = {};
};

/// core::trace_ray's queries (render.h SceneTracer) with the work of each ray recorded: by depth for
/// the closest hits, under "shadow" for the shadow rays of each shading.
struct RecordingTracer {
    RayProfile& profile;
    PixelWork& pixel;

    static void record(RayWork& w, std::uint32_t& leaves, std::uint32_t& tests, const core::RayCounters& c) {
        w.leaves += c.leaves;
        w.culled += c.culled;
        w.splat_tests += c.splat_tests;
        leaves += c.leaves;
        tests += c.splat_tests;
    }
    bool closest(const core::SceneView& s, const core::PendingRay& p, core::SurfaceHit& h,
                 core::RayCounters& c) const {
        core::RayCounters own;
        const bool hit = core::closest_hit_scene(s, p.ray, h, own);
        ++profile.depth[p.depth].rays;
        record(profile.depth[p.depth], pixel.leaves[p.depth], pixel.tests[p.depth], own);
        c += own;
        return hit;
    }
    core::Vec3 shade(const core::SceneView& s, const core::PendingRay& p, const core::SurfaceHit& h,
                     core::RayCounters& c) const {
        constexpr std::uint32_t shadow_slot = core::k_max_bounces + 1;
        core::RayCounters own;
        const core::Vec3 color = core::shade_hit(s, p.ray, h, own);
        profile.shadow.rays += own.shadow;
        record(profile.shadow, pixel.leaves[shadow_slot], pixel.tests[shadow_slot], own);
        c += own;
        return color;
    }
};

void add(RayWork& a, const RayWork& b) {
    a.rays += b.rays;
    a.leaves += b.leaves;
    a.culled += b.culled;
    a.splat_tests += b.splat_tests;
}

}  // namespace

RayProfile profile_rays(const core::SceneView& scene, const core::PinholeCamera& camera, std::uint32_t width,
                        std::uint32_t height) {
    const std::uint32_t depths = std::min(scene.params.max_bounces, core::k_max_bounces) + 1;
    const std::uint32_t warps_x = (width + k_warp_w - 1) / k_warp_w,
                        warps_y = (height + k_warp_h - 1) / k_warp_h;
    const std::uint32_t warps = warps_x * warps_y;
    RayProfile total;
    total.depth.resize(depths);
    double sums[6] = {};  // leaves: work, per-bounce max, whole-path max; tests: the same
    std::mutex mutex;
    std::atomic<std::uint32_t> next{0};
    auto job = [&] {
        RayProfile local;
        local.depth.resize(depths);
        double s[6] = {};
        for (;;) {
            const std::uint32_t wi = next.fetch_add(1);
            if (wi >= warps) break;
            const std::uint32_t x0 = (wi % warps_x) * k_warp_w, y0 = (wi / warps_x) * k_warp_h;
            PixelWork px[k_warp_w * k_warp_h];
            for (std::uint32_t t = 0; t < k_warp_w * k_warp_h; ++t) {
                const std::uint32_t x = x0 + t % k_warp_w, y = y0 + t / k_warp_w;
                if (x >= width || y >= height) continue;  // idle lanes
                core::RayCounters c;
                core::trace_ray(scene, core::primary_ray(camera, x, y, width, height), c,
                                RecordingTracer{local, px[t]});
                local.dropped += c.dropped;
            }
            // Shadow rays belong to the bounce that spawned them; count them as one more phase.
            for (int kind = 0; kind < 2; ++kind) {
                double work = 0, per_bounce = 0;
                std::uint32_t whole = 0;
                for (std::uint32_t d = 0; d < core::k_max_bounces + 2; ++d) {
                    std::uint32_t most = 0;
                    for (const PixelWork& p : px) {
                        const std::uint32_t v = kind == 0 ? p.leaves[d] : p.tests[d];
                        work += v;
                        most = std::max(most, v);
                    }
                    per_bounce += most;
                }
                for (const PixelWork& p : px) {
                    std::uint32_t sum = 0;
                    for (std::uint32_t d = 0; d < core::k_max_bounces + 2; ++d)
                        sum += kind == 0 ? p.leaves[d] : p.tests[d];
                    whole = std::max(whole, sum);
                }
                s[kind * 3 + 0] += work;
                s[kind * 3 + 1] += 32.0 * per_bounce;
                s[kind * 3 + 2] += 32.0 * whole;
            }
        }
        std::lock_guard<std::mutex> lock(mutex);
        for (std::uint32_t d = 0; d < depths; ++d) add(total.depth[d], local.depth[d]);
        add(total.shadow, local.shadow);
        total.dropped += local.dropped;
        for (int i = 0; i < 6; ++i) sums[i] += s[i];
    };
    const unsigned n = prt::available_cores();
    std::vector<std::thread> threads;
    for (unsigned i = 1; i < n; ++i) threads.emplace_back(job);
    job();
    for (std::thread& t : threads) t.join();
    total.leaves_simt_per_bounce = sums[1] > 0 ? sums[0] / sums[1] : 1.0;
    total.leaves_simt_whole_path = sums[2] > 0 ? sums[0] / sums[2] : 1.0;
    total.tests_simt_per_bounce = sums[4] > 0 ? sums[3] / sums[4] : 1.0;
    total.tests_simt_whole_path = sums[5] > 0 ? sums[3] / sums[5] : 1.0;
    while (total.depth.size() > 1 && total.depth.back().rays == 0) total.depth.pop_back();
    return total;
}

nlohmann::json RayProfile::to_json() const {
    auto one = [](const std::string& kind, const RayWork& w) {
        return nlohmann::json{{"kind", kind},
                              {"rays", w.rays},
                              {"leaves_per_ray", w.per_ray(w.leaves)},
                              {"culled_leaves_per_ray", w.per_ray(w.culled)},
                              {"splat_tests_per_ray", w.per_ray(w.splat_tests)}};
    };
    nlohmann::json j;
    for (std::size_t d = 0; d < depth.size(); ++d)
        j["kinds"].push_back(one(d == 0 ? "primary" : "bounce " + std::to_string(d), depth[d]));
    j["kinds"].push_back(one("shadow", shadow));
    if (dropped) j["dropped_rays"] = dropped;  // never seen: the ray stack holds a whole depth-first tree
    j["simt_efficiency"] = {{"leaves_per_bounce", leaves_simt_per_bounce},
                            {"leaves_whole_path", leaves_simt_whole_path},
                            {"splat_tests_per_bounce", tests_simt_per_bounce},
                            {"splat_tests_whole_path", tests_simt_whole_path}};
    return j;
}

std::string RayProfile::table() const {
    std::string out;
    char line[256];
    std::snprintf(line, sizeof(line), "  %-10s %12s %12s %14s %14s\n", "rays", "count", "leaves/ray",
                  "culled/ray", "tests/ray");
    out += line;
    auto row = [&](const std::string& kind, const RayWork& w) {
        std::snprintf(line, sizeof(line), "  %-10s %12llu %12.2f %14.2f %14.2f\n", kind.c_str(),
                      static_cast<unsigned long long>(w.rays), w.per_ray(w.leaves), w.per_ray(w.culled),
                      w.per_ray(w.splat_tests));
        out += line;
    };
    for (std::size_t d = 0; d < depth.size(); ++d)
        row(d == 0 ? "primary" : "bounce " + std::to_string(d), depth[d]);
    if (shadow.rays) row("shadow", shadow);
    if (dropped) {
        std::snprintf(line, sizeof(line), "  %llu secondary rays dropped (ray stack full)\n",
                      static_cast<unsigned long long>(dropped));
        out += line;
    }
    std::snprintf(
        line, sizeof(line),
        "  SIMT efficiency (32-lane warps, 8x4 pixels): leaves %.2f per bounce, %.2f over the whole "
        "path; splat tests %.2f / %.2f\n",
        leaves_simt_per_bounce, leaves_simt_whole_path, tests_simt_per_bounce, tests_simt_whole_path);
    out += line;
    return out;
}

}  // namespace prt::player
