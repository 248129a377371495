// The MLS core (prt/core/mls.h) in a CUDA kernel, one thread per ray, against the same function on
// the CPU (one body, both backends), through the BVH over the leaves and through the kd-tree. Device float
// arithmetic contracts a * b + c into FMAs, so hit distances may differ in the last bits and a grazing ray
// may flip between hit and miss: t is compared with a tolerance and a few flips are allowed. Also reports
// device rays per second. Label gpu; skips with a message where no CUDA device is present.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gpu_test_util.cuh"
#include "mls_test_util.h"
#include "mls_trace.h"

namespace {

using namespace prt;
using prt::test::DeviceBuffers;
using prt::test::have_device;

__global__ void trace_kernel(core::MlsView view, const core::Ray* rays, std::uint32_t n,
                             core::MlsParams params, core::MlsHit* hits, std::uint32_t* found,
                             core::MlsStats* stats) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    core::MlsHit h;
    core::MlsStats st;
    const core::Ray r = rays[i];
    found[i] =
        core::trace_mls<float>(view, r.origin, r.dir, r.t_max, core::ray_inside(r), params, h, st) ? 1u : 0u;
    hits[i] = h;
    stats[i] = st;
}

__global__ void occluded_kernel(core::MlsView view, const core::Ray* rays, std::uint32_t n,
                                core::MlsParams params, std::uint32_t* occluded) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    core::MlsStats st;
    const core::Ray r = rays[i];
    occluded[i] =
        core::mls_occluded<float>(view, r.origin, r.dir, r.t_max, core::ray_inside(r), params, st) ? 1u : 0u;
}

/// One walk's GPU rays against the CPU's: `view` the host view, `dev` the same on the device.
void compare_walk(const char* walk, const core::MlsView& host, const core::MlsView& dev, DeviceBuffers& d) {
    // 512 x 512 primary rays of a pinhole camera at distance 4 looking at the sphere.
    const std::vector<core::Ray> rays = prt::test::pinhole_rays(core::Vec3{0.8f, 1.2f, 3.6f}, 512, 20.0f);
    const auto n = static_cast<std::uint32_t>(rays.size());
    const core::Ray* d_rays = d.upload(rays.data(), n);
    core::MlsHit* d_hits = d.alloc<core::MlsHit>(n);
    std::uint32_t* d_found = d.alloc<std::uint32_t>(n);
    core::MlsStats* d_stats = d.alloc<core::MlsStats>(n);
    ASSERT_TRUE(d_rays && d_hits && d_found && d_stats);
    const core::MlsParams params;
    const unsigned block = 128, grid = (n + block - 1) / block;
    trace_kernel<<<grid, block>>>(dev, d_rays, n, params, d_hits, d_found, d_stats);  // warm-up
    PRT_CUDA_CHECK(cudaGetLastError());
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    std::vector<float> ms;
    PRT_CUDA_CHECK(prt::test::time_launches(
        11, [&] { trace_kernel<<<grid, block>>>(dev, d_rays, n, params, d_hits, d_found, d_stats); }, ms));
    std::vector<core::MlsHit> hits;
    std::vector<std::uint32_t> found;
    std::vector<core::MlsStats> stats;
    PRT_CUDA_CHECK(prt::test::download(hits, d_hits, n));
    PRT_CUDA_CHECK(prt::test::download(found, d_found, n));
    PRT_CUDA_CHECK(prt::test::download(stats, d_stats, n));

    const mls::TraceResult cpu = mls::trace_rays(host, rays, params, 0);
    std::uint32_t flips = 0, both = 0;
    double worst = 0;
    std::uint64_t splats = 0, steps = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        splats += stats[i].splats;
        steps += stats[i].traversal_steps;
        if ((found[i] != 0) != (cpu.found[i] != 0)) {
            ++flips;
            continue;
        }
        if (!found[i]) continue;
        ++both;
        worst = std::max(worst, double(std::abs(hits[i].t - cpu.hits[i].t)));
    }
    std::printf(
        "[ measured ] MLS on the GPU, %s walk: %.1f Mrays/s (median of %zu, 512x512 primary, sphere 100k "
        "points); %u hits, %u flips, max |dt| %.2e; %.1f splats, %.1f traversal steps per ray\n",
        walk, n / (ms[ms.size() / 2] * 1e3), ms.size(), both, flips, worst, double(splats) / n,
        double(steps) / n);
    EXPECT_GT(both, n / 4);
    EXPECT_LE(flips, n / 10000 + 5);
    EXPECT_LT(worst, 1e-3);  // distance ~3.6: relative 3e-4 (grazing rays take other roots, counted above)

    // Shadow rays agree with the closest hits.
    std::uint32_t* d_occ = d.alloc<std::uint32_t>(n);
    occluded_kernel<<<grid, block>>>(dev, d_rays, n, params, d_occ);
    PRT_CUDA_CHECK(cudaGetLastError());
    std::vector<std::uint32_t> occ;
    PRT_CUDA_CHECK(prt::test::download(occ, d_occ, n));
    std::uint32_t disagree = 0;
    for (std::uint32_t i = 0; i < n; ++i) disagree += (occ[i] != 0) != (found[i] != 0);
    EXPECT_LE(disagree, n / 10000 + 5);
}

TEST(MlsGpu, KernelMatchesTheCpu) {
    std::string why;
    if (!have_device(why)) GTEST_SKIP() << why;
    const mls_test::PointSet s = mls_test::fibonacci_sphere(100000);
    const mls::MlsModel m = mls_test::build(s);
    const core::MlsView host = mls::make_view(m);
    ASSERT_NE(host.bvh_nodes, nullptr);
    DeviceBuffers d;
    core::MlsView dev = host;
    dev.nodes = d.upload(host.nodes, host.node_count);
    dev.refs = d.upload(host.refs, host.ref_count);
    dev.splats = d.upload(host.splats, host.splat_count);
    dev.bvh_nodes = d.upload(host.bvh_nodes, host.bvh_node_count);
    dev.bvh_leaves = d.upload(host.bvh_leaves, host.bvh_leaf_count);
    ASSERT_TRUE(dev.nodes && dev.refs && dev.splats && dev.bvh_nodes && dev.bvh_leaves) << "upload failed";
    compare_walk("BVH", host, dev, d);
    // The kd walk (pools without the BVH sections).
    core::MlsView host_kd = host, dev_kd = dev;
    host_kd.bvh_nodes = dev_kd.bvh_nodes = nullptr;
    host_kd.bvh_leaves = dev_kd.bvh_leaves = nullptr;
    compare_walk("kd", host_kd, dev_kd, d);
}

}  // namespace
