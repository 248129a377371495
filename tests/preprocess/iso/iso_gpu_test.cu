// The ISO core (prt/core/iso.h) in a CUDA kernel, one thread per ray, against the same function
// on the CPU (one body, both backends), for quantized and float leaves: primary rays, inside
// (refracted) rays from the hits, and shadow rays. Device float arithmetic contracts a * b + c into
// FMAs, so hit distances may differ in the last bits and a grazing ray may flip between hit and
// miss: t is compared with a tolerance and a few flips are allowed. Also reports device rays/s
// (CUDA events, median of 11 launches after a warm-up). Label gpu; skips with a message where no
// CUDA device is present.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gpu_test_util.cuh"
#include "iso_test_util.h"

namespace {

using namespace prt;
using prt::test::DeviceBuffers;
using prt::test::have_device;

__global__ void trace_kernel(core::IsoView view, const core::Ray* rays, std::uint32_t n,
                             core::IsoParams params, core::IsoHit* hits, std::uint32_t* found) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    core::IsoHit h;
    core::IsoStats st;
    const core::Ray r = rays[i];
    found[i] = core::trace_iso(view, r.origin, r.dir, r.t_max, core::ray_inside(r), params, h, st) ? 1u : 0u;
    hits[i] = h;
}

__global__ void occluded_kernel(core::IsoView view, const core::Ray* rays, std::uint32_t n,
                                core::IsoParams params, std::uint32_t* occluded) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    core::IsoStats st;
    const core::Ray r = rays[i];
    occluded[i] =
        core::iso_occluded(view, r.origin, r.dir, r.t_max, core::ray_inside(r), params, st) ? 1u : 0u;
}

/// CPU reference for the same rays.
void trace_cpu(const core::IsoView& v, const std::vector<core::Ray>& rays, const core::IsoParams& p,
               std::vector<core::IsoHit>& hits, std::vector<std::uint32_t>& found,
               std::vector<std::uint32_t>& occ) {
    hits.resize(rays.size());
    found.resize(rays.size());
    occ.resize(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) {
        core::IsoStats st;
        const core::Ray& r = rays[i];
        found[i] =
            core::trace_iso(v, r.origin, r.dir, r.t_max, core::ray_inside(r), p, hits[i], st) ? 1u : 0u;
        occ[i] = core::iso_occluded(v, r.origin, r.dir, r.t_max, core::ray_inside(r), p, st) ? 1u : 0u;
    }
}

TEST(IsoGpu, KernelMatchesTheCpu) {
    std::string why;
    if (!have_device(why)) GTEST_SKIP() << why;
    const iso_test::PointSet s = iso_test::synth_points(iso_test::torus_shape(1.0, 0.4), 200000, 0.0, true);
    iso::BuildOptions o;
    o.storage = iso::Storage::both;
    const iso::IsoModel m = iso::build_iso(s.input(), o);
    DeviceBuffers d;
    std::uint32_t* d_nodes = d.upload(m.nodes.data(), m.nodes.size());
    pool::IsoLeafQ8* d_q8 = d.upload(m.leaves_q8.data(), m.leaves_q8.size());
    pool::IsoLeafF32* d_f32 = d.upload(m.leaves_f32.data(), m.leaves_f32.size());
    ASSERT_TRUE(d_nodes && d_q8 && d_f32) << "upload failed";

    // 1024 x 1024 primary rays of a pinhole camera looking at the torus from above.
    const std::vector<core::Ray> rays = prt::test::pinhole_rays(core::Vec3{0.6f, 2.4f, 2.8f}, 1024, 22.0f);
    const core::IsoParams params;
    for (int q8 = 1; q8 >= 0; --q8) {
        core::IsoView host = iso::make_view(m, q8 == 1);
        core::IsoView dev = host;
        dev.tree.nodes = d_nodes;
        dev.leaves_q8 = d_q8;
        dev.leaves_f32 = d_f32;
        // Primary rays, then refracted (inside) rays from every CPU hit along the same direction.
        std::vector<core::IsoHit> cpu_hits;
        std::vector<std::uint32_t> cpu_found, cpu_occ;
        trace_cpu(host, rays, params, cpu_hits, cpu_found, cpu_occ);
        std::vector<core::Ray> all = rays;
        for (std::size_t i = 0; i < rays.size(); i += 7)
            if (cpu_found[i])
                all.push_back({cpu_hits[i].position, rays[i].dir, core::k_inf, core::k_ray_inside});
        std::vector<core::IsoHit> ref_hits;
        std::vector<std::uint32_t> ref_found, ref_occ;
        trace_cpu(host, all, params, ref_hits, ref_found, ref_occ);

        const auto n = static_cast<std::uint32_t>(all.size());
        const core::Ray* d_rays = d.upload(all.data(), n);
        core::IsoHit* d_hits = d.alloc<core::IsoHit>(n);
        std::uint32_t* d_found = d.alloc<std::uint32_t>(n);
        std::uint32_t* d_occ = d.alloc<std::uint32_t>(n);
        ASSERT_TRUE(d_rays && d_hits && d_found && d_occ);
        const unsigned block = 128;
        const std::uint32_t primary = static_cast<std::uint32_t>(rays.size());
        trace_kernel<<<(n + block - 1) / block, block>>>(dev, d_rays, n, params, d_hits, d_found);
        PRT_CUDA_CHECK(cudaGetLastError());
        PRT_CUDA_CHECK(cudaDeviceSynchronize());
        // Timing: the primary rays only.
        std::vector<float> ms;
        PRT_CUDA_CHECK(prt::test::time_launches(11, [&] {
            trace_kernel<<<(primary + block - 1) / block, block>>>(dev, d_rays, primary, params, d_hits,
                                                                   d_found);
        }, ms));
        trace_kernel<<<(n + block - 1) / block, block>>>(dev, d_rays, n, params, d_hits, d_found);
        occluded_kernel<<<(n + block - 1) / block, block>>>(dev, d_rays, n, params, d_occ);
        PRT_CUDA_CHECK(cudaGetLastError());
        std::vector<core::IsoHit> hits;
        std::vector<std::uint32_t> found, occ;
        PRT_CUDA_CHECK(prt::test::download(hits, d_hits, n));
        PRT_CUDA_CHECK(prt::test::download(found, d_found, n));
        PRT_CUDA_CHECK(prt::test::download(occ, d_occ, n));
        std::uint32_t flips = 0, both = 0, inside = 0, occ_flips = 0;
        double worst_t = 0, worst_deg = 0;
        for (std::uint32_t i = 0; i < n; ++i) {
            occ_flips += (occ[i] != 0) != (ref_occ[i] != 0);
            if ((found[i] != 0) != (ref_found[i] != 0)) {
                ++flips;
                continue;
            }
            if (!found[i]) continue;
            ++both;
            inside += i >= primary;
            EXPECT_EQ(hits[i].front, ref_hits[i].front) << "ray " << i;
            const double dt = double(std::abs(hits[i].t - ref_hits[i].t)) / std::max(1.0f, ref_hits[i].t);
            if (dt > 1e-3) {  // a grazing ray that found another root: counted with the flips
                ++flips;
                continue;
            }
            worst_t = std::max(worst_t, dt);
            worst_deg = std::max(worst_deg, iso_test::angle_deg(iso_test::d3(hits[i].normal),
                                                                iso_test::d3(ref_hits[i].normal)));
        }
        std::printf(
            "[ measured ] ISO on the GPU (%s leaves): %.1f Mrays/s (median of %zu, 1024x1024 primary, torus "
            "200k points, %u leaves); %u hits (%u inside rays), %u flips, max relative |dt| %.2e, max normal "
            "%.3f deg, %u shadow flips\n",
            q8 ? "q8" : "f32", primary / (ms[ms.size() / 2] * 1e3), ms.size(), m.info.leaf_count, both,
            inside, flips, worst_t, worst_deg, occ_flips);
        EXPECT_GT(both, primary / 5);
        EXPECT_GT(inside, 1000u);
        EXPECT_LE(flips, n / 10000 + 5);
        EXPECT_LE(occ_flips, n / 10000 + 5);
        EXPECT_LT(worst_t, 1e-3);
        EXPECT_LT(worst_deg, 0.5);
    }
}

}  // namespace
