// PointRT CUDA: prt-photons' kernel (thesis 5.4.1). One thread traces one photon with
// core::trace_photon(), the function the CPU path runs, over the device copy of the scene
// (DeviceScene, shared with the renderer). Consecutive threads take consecutive photons: the
// per_pixel photons of one pixel, then the next pixel of the row, so a warp's rays leave the light
// in nearly the same direction and walk the same octree nodes (the coherence the thesis's Z-order
// ray mapping buys for primary rays, 2.3).
//
// Deposits are appended through one atomic counter into a buffer sized for the launch; a launch
// whose deposits overflow it is run again with a buffer of the counted size (photons are
// counter-hashed, so the rerun deposits exactly the same photons). Power tallies are reduced per
// warp and added in double.
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/cuda/device.h"
#include "prt/cuda/device_scene.h"
#include "prt/cuda/photons_cuda.h"

namespace prt::cuda {

namespace {

constexpr std::uint32_t k_block = 256;
/// Photons per launch: ~15 waves of 2048-thread SMs on an H100; progress between launches.
constexpr std::uint64_t k_photons_per_launch = 1ull << 22;

/// Tally slots: 6 categories x RGB, then deposits, specular hits, rays.
constexpr int k_tally_floats = 18;
constexpr int k_tally_slots = 21;

__device__ __forceinline__ float warp_sum(float v) {
    for (int o = 16; o > 0; o >>= 1) v += __shfl_down_sync(0xffffffffu, v, o);
    return v;
}

__global__ void __launch_bounds__(k_block)
    shoot_kernel(const core::SceneView scene, const core::PhotonShootParams params, std::uint64_t first,
                 std::uint64_t count, std::uint64_t per_light, core::PhotonDeposit* deposits,
                 std::uint64_t capacity, unsigned long long* deposit_count, double* tally) {
    const std::uint64_t i = static_cast<std::uint64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    core::PhotonTallyF t;
    if (i < count) {
        const std::uint64_t g = first + i;
        const std::uint32_t light = static_cast<std::uint32_t>(g / per_light);
        core::trace_photon(scene, params, light, g - light * per_light, t, [&](const core::PhotonDeposit& d) {
            const unsigned long long slot = atomicAdd(deposit_count, 1ull);
            if (slot < capacity) deposits[slot] = d;
        });
    }
    const float v[k_tally_slots] = {t.emitted.x,   t.emitted.y,   t.emitted.z,       t.direct.x,
                                    t.direct.y,    t.direct.z,    t.deposited.x,     t.deposited.y,
                                    t.deposited.z, t.absorbed.x,  t.absorbed.y,      t.absorbed.z,
                                    t.escaped.x,   t.escaped.y,   t.escaped.z,       t.truncated.x,
                                    t.truncated.y, t.truncated.z, float(t.deposits), float(t.specular_hits),
                                    float(t.rays)};
    // Every lane reaches the shuffles (threads past `count` contribute zeros).
    PRT_UNROLL
    for (int k = 0; k < k_tally_slots; ++k) {
        const float s = warp_sum(v[k]);
        if ((threadIdx.x & 31u) == 0 && s != 0.0f) atomicAdd(&tally[k], static_cast<double>(s));
    }
}

}  // namespace

bool photons_device_available(std::string* why) {
    return device_available(why);
}

PhotonsCudaResult shoot_photons_cuda(const core::SceneView& host, const core::PhotonShootParams& params,
                                     const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    const auto setup_start = std::chrono::steady_clock::now();
    PRT_CUDA_CHECK(cudaSetDevice(0));
    PhotonsCudaResult result;
    cudaDeviceProp prop{};
    PRT_CUDA_CHECK(cudaGetDeviceProperties(&prop, 0));
    result.device = prop.name;
    DeviceScene scene;
    scene.upload(host, nullptr);
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    result.setup_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_start).count();
    const std::uint64_t per_light = core::photons_per_light(params);
    const std::uint64_t total = per_light * core::photon_light_count(host);
    DeviceBuffer<core::PhotonDeposit> d_deposits;
    std::uint64_t capacity =
        std::min<std::uint64_t>(k_photons_per_launch / 4, std::max<std::uint64_t>(total, 1));
    d_deposits.resize(capacity);
    DeviceBuffer<unsigned long long> d_count(1);
    DeviceBuffer<double> d_tally(k_tally_slots);
    PRT_CUDA_CHECK(cudaMemset(d_tally.data(), 0, d_tally.bytes()));
    cudaEvent_t start, stop;
    PRT_CUDA_CHECK(cudaEventCreate(&start));
    PRT_CUDA_CHECK(cudaEventCreate(&stop));
    std::vector<double> tally_before(k_tally_slots, 0.0);
    for (std::uint64_t first = 0; first < total;) {
        const std::uint64_t count = std::min(k_photons_per_launch, total - first);
        PRT_CUDA_CHECK(
            cudaMemcpy(tally_before.data(), d_tally.data(), d_tally.bytes(), cudaMemcpyDeviceToHost));
        PRT_CUDA_CHECK(cudaMemset(d_count.data(), 0, d_count.bytes()));
        PRT_CUDA_CHECK(cudaEventRecord(start));
        launch_kernel(launch_1d(count, k_block), shoot_kernel, scene.view(), params, first, count, per_light,
                      d_deposits.data(), capacity, d_count.data(), d_tally.data());
        PRT_CUDA_CHECK(cudaEventRecord(stop));
        PRT_CUDA_CHECK(cudaEventSynchronize(stop));
        float ms = 0.0f;
        PRT_CUDA_CHECK(cudaEventElapsedTime(&ms, start, stop));
        result.kernel_seconds += ms * 1e-3;
        unsigned long long n = 0;
        d_count.download(&n, 1);
        PRT_CUDA_CHECK(cudaDeviceSynchronize());
        if (n > capacity) {  // overflow: undo this launch's tallies and run it again, larger
            PRT_CUDA_CHECK(
                cudaMemcpy(d_tally.data(), tally_before.data(), d_tally.bytes(), cudaMemcpyHostToDevice));
            capacity = n;
            d_deposits.resize(capacity);
            continue;
        }
        const std::size_t old = result.deposits.size();
        result.deposits.resize(old + n);
        d_deposits.download(result.deposits.data() + old, n);
        PRT_CUDA_CHECK(cudaDeviceSynchronize());
        first += count;
        if (progress) progress(first, total);
    }
    cudaEventDestroy(start);
    cudaEventDestroy(stop);
    double t[k_tally_slots];
    d_tally.download(t, k_tally_slots);
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    double* dst[6] = {result.tally.emitted,  result.tally.direct,  result.tally.deposited,
                      result.tally.absorbed, result.tally.escaped, result.tally.truncated};
    for (int k = 0; k < k_tally_floats; ++k) dst[k / 3][k % 3] = t[k];
    result.tally.deposits = static_cast<std::uint64_t>(t[18] + 0.5);
    result.tally.specular_hits = static_cast<std::uint64_t>(t[19] + 0.5);
    result.tally.rays = static_cast<std::uint64_t>(t[20] + 0.5);
    result.tally.photons = total;
    return result;
}

}  // namespace prt::cuda
