// The patch core (prt/core/patch.h) in a CUDA kernel, one thread per ray, against the same
// functions on the CPU (Mitsuba style: one body, both backends). GPU doubles contract a * b + c into
// FMAs, so roots may differ in the last bits: t is compared with a relative tolerance and a few
// hit/miss flips are allowed only for grazing rays. Also reports rays per second on the device.
// Label gpu; skips with a message where no CUDA device is present.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "gpu_test_util.cuh"
#include "patch_build.h"
#include "patch_file.h"
#include "patch_pool.h"
#include "prt/core/patch.h"
#include "prt/runtime/surface_pools.h"

namespace {

using prt::core::DVec3;
using prt::core::PatchHit;
using prt::core::PatchRay;
using prt::core::PatchTraceParams;
using prt::core::PatchView;
using prt::test::have_device;

__global__ void trace_kernel(PatchView view, const PatchRay* rays, std::uint32_t n, PatchTraceParams params,
                             PatchHit* hits, std::uint32_t* flags) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    PatchHit h;
    flags[i] = prt::core::trace_patches(view, rays[i], params, h) ? 1u : 0u;
    hits[i] = h;
}

/// Device copies of a pool's patch sections (freed on destruction).
struct DeviceView {
    PatchView view;
    prt::test::DeviceBuffers memory;
};

/// Pinhole camera rays (local frame) looking at the view's box centre, z up.
std::vector<PatchRay> camera_rays(const prt::pool::PatchInfo& info, int size, double az, double el) {
    const double k = 3.14159265358979323846 / 180.0;
    const DVec3 lo{info.bounds_min[0], info.bounds_min[1], info.bounds_min[2]};
    const DVec3 hi{info.bounds_max[0], info.bounds_max[1], info.bounds_max[2]};
    const DVec3 c = (lo + hi) * 0.5;
    const double r = 0.5 * prt::core::length(hi - lo);
    const DVec3 dir{std::cos(el * k) * std::cos(az * k), std::cos(el * k) * std::sin(az * k),
                    std::sin(el * k)};
    const DVec3 eye = c + dir * (r / (1.5 * std::sin(20 * k)));
    const DVec3 f = -dir;
    DVec3 right = prt::core::cross(f, DVec3{0, 0, 1});
    right = right * (1.0 / prt::core::length(right));
    const DVec3 up = prt::core::cross(right, f);
    const double t = std::tan(20 * k);
    std::vector<PatchRay> rays;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double sx = ((x + 0.5) / size * 2 - 1) * t, sy = (1 - (y + 0.5) / size * 2) * t;
            rays.push_back({eye, f + right * sx + up * sy, 1e30, 0});
        }
    return rays;
}

void compare_on_device(const prt::pool::PoolFile& pool, const std::string& name) {
    const PatchView host = prt::rt::load_patch_view(pool);
    const auto& info = pool.array<prt::pool::PatchInfo>(prt::pool::SectionType::patch_info)[0];
    DeviceView d;
    d.view = host;
    d.view.nets = d.memory.upload(host.nets, host.patch_count);
    d.view.bvh = d.memory.upload(host.bvh, host.bvh_node_count);
    d.view.nodes = d.memory.upload(host.nodes, std::size_t(host.patch_count) * host.subpatch_nodes);
    ASSERT_TRUE(d.view.nets && d.view.bvh && d.view.nodes) << "upload failed";
    const int size = 512;
    const std::vector<PatchRay> rays = camera_rays(info, size, -60, 25);
    const std::uint32_t n = static_cast<std::uint32_t>(rays.size());
    const PatchRay* d_rays = d.memory.upload(rays.data(), n);
    PatchHit* d_hits = d.memory.alloc<PatchHit>(n);
    std::uint32_t* d_flags = d.memory.alloc<std::uint32_t>(n);
    ASSERT_TRUE(d_rays && d_hits && d_flags) << "device allocation failed";
    const PatchTraceParams params;
    const unsigned block = 128, grid = (n + block - 1) / block;
    trace_kernel<<<grid, block>>>(d.view, d_rays, n, params, d_hits, d_flags);  // warm-up
    PRT_CUDA_CHECK(cudaGetLastError());
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    std::vector<float> ms;
    PRT_CUDA_CHECK(prt::test::time_launches(
        20, [&] { trace_kernel<<<grid, block>>>(d.view, d_rays, n, params, d_hits, d_flags); }, ms));
    std::vector<PatchHit> hits;
    std::vector<std::uint32_t> flags;
    PRT_CUDA_CHECK(prt::test::download(hits, d_hits, n));
    PRT_CUDA_CHECK(prt::test::download(flags, d_flags, n));

    std::uint32_t both = 0, flips = 0, cpu_hits = 0;
    double worst = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        PatchHit h;
        const bool cpu = prt::core::trace_patches(host, rays[i], params, h);
        cpu_hits += cpu;
        if (cpu && flags[i]) {
            ++both;
            const double rel = std::fabs(h.t - hits[i].t) / h.t;
            worst = std::max(worst, rel);
            EXPECT_LT(rel, 1e-9) << name << " ray " << i;
            EXPECT_TRUE(std::isfinite(hits[i].normal.x) && std::isfinite(hits[i].normal.z));
        } else if (cpu != (flags[i] != 0)) {
            ++flips;
            const PatchHit& g = cpu ? h : hits[i];
            const double c =
                std::fabs(prt::core::dot(g.normal, rays[i].dir)) / prt::core::length(rays[i].dir);
            EXPECT_LT(c, 0.1) << name << " ray " << i << ": hit/miss differs away from a silhouette";
        }
    }
    EXPECT_GT(both, n / 10) << name;
    EXPECT_LE(flips, std::max<std::uint32_t>(2, cpu_hits / 10000)) << name;
    std::printf(
        "[ gpu      ] %s: %u rays, %u hits, %u flips, worst relative t difference %.2e, kernel %.3f ms "
        "(median of 20), %.1f M rays/s\n",
        name.c_str(), n, both, flips, worst, ms[ms.size() / 2], n / (ms[ms.size() / 2] * 1e-3) / 1e6);
}

prt::pool::PoolFile build(std::vector<prt::pool::PatchControlNet> nets) {
    const auto model = prt::patches::build_patch_model(std::move(nets), prt::patches::BuildOptions{});
    prt::pool::PoolWriter w;
    prt::patches::write_patch_sections(model, w);
    return prt::pool::PoolFile::from_bytes(w.serialize(), "gpu_test.pool");
}

TEST(PatchGpu, SyntheticPatchesMatchTheCpu) {
    std::string why;
    if (!have_device(why)) GTEST_SKIP() << why;
    std::mt19937_64 rng(21);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    std::vector<prt::pool::PatchControlNet> nets;
    for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) {
            prt::pool::PatchControlNet n{};
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j)
                    n.p[4 * i + j] = {a + i / 3.0 + 0.05 * jitter(rng), b + j / 3.0 + 0.05 * jitter(rng),
                                      0.4 * std::sin(a + i / 3.0) * std::cos(b + j / 3.0) + jitter(rng)};
            nets.push_back(n);
        }
    compare_on_device(build(nets), "synthetic 8x8");
}

TEST(PatchGpu, TeapotMatchesTheCpu) {
    std::string why;
    if (!have_device(why)) GTEST_SKIP() << why;
    // The shared teapot, or a pool named by PRT_PATCH_POOL (machines without ../shared/data).
    const char* env = std::getenv("PRT_PATCH_POOL");
    if (env) {
        compare_on_device(prt::pool::PoolFile::open(env), env);
        return;
    }
    const std::string teapot = std::string(PRT_SHARED_DATA_DIR) + "/bezier/teapot";
    if (!std::filesystem::exists(teapot)) GTEST_SKIP() << "shared data not found: " << teapot;
    compare_on_device(build(prt::patches::read_patch_file(teapot, prt::patches::PatchFormat::automatic).nets),
                      "teapot");
}

}  // namespace
