// PointRT CUDA: prt-lightmap's kernel (thesis 5.3). One block per light-map sample: every thread
// finds the sample's start (core::light_map_start: the same probe, the same answer) and traces
// every k_block-th of its paths (core::light_map_sample_path), the functions the CPU path runs, over
// the device copy of the scene (DeviceScene, shared with the renderer and prt-photons); the block
// sums them. So both backends trace the same paths and differ only by rounding (summation order,
// fast math; tests/preprocess/lightmap/lightmap_gpu_test.cpp). One thread per sample looping over
// its 64 paths left the H100 under two waves of long threads (2.16 s for the 1M room's 455k
// samples); a sample's paths in parallel keep it full. Samples go up in launches of
// k_samples_per_launch, so progress is reported between them.
#include <cuda_runtime.h>

#include <algorithm>

#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/cuda/device.h"
#include "prt/cuda/device_scene.h"
#include "prt/cuda/lightmap_cuda.h"

namespace prt::cuda {

namespace {

constexpr std::uint32_t k_block = 64;  ///< threads per sample (its paths: tp.rays, default 64)
/// Samples per launch (a block each): progress between launches.
constexpr std::uint64_t k_samples_per_launch = 1ull << 16;

/// K (KernelMask): the surfaces the scene holds; splat-only scenes get a kernel without the others'
/// code (and their registers), as the renderer's do.
template <std::uint32_t K>
__global__ void __launch_bounds__(k_block)
    light_map_kernel(const core::SceneView scene, const core::LightMapTraceParams params,
                     const core::LightMapSampleIn* in, core::LightMapSampleOut* out,
                     std::uint64_t first_index) {
    const std::uint64_t j = blockIdx.x;
    const core::LightMapSampleIn sample = in[j];
    core::RayCounters c;
    core::SurfaceHit hit;
    core::Vec3 side;
    const bool started = core::light_map_start<K>(scene, sample, hit, side, c);
    core::Vec3 sum{0, 0, 0};
    if (started)
        for (std::uint32_t k = threadIdx.x; k < params.rays; k += k_block)
            sum += core::light_map_sample_path<K>(scene, params, sample, hit, side, first_index + j, k, c);
    __shared__ float partial[3][k_block];
    partial[0][threadIdx.x] = sum.x;
    partial[1][threadIdx.x] = sum.y;
    partial[2][threadIdx.x] = sum.z;
    __syncthreads();
    for (std::uint32_t half = k_block / 2; half > 0; half /= 2) {
        if (threadIdx.x < half)
            for (int a = 0; a < 3; ++a) partial[a][threadIdx.x] += partial[a][threadIdx.x + half];
        __syncthreads();
    }
    if (threadIdx.x != 0) return;
    core::LightMapSampleOut o;
    o.settled = started ? 1u : 0u;
    o.side = side;
    o.position = sample.settle_reach > 0.0f && started ? hit.position : sample.position;
    const float inv = params.rays > 0 ? 1.0f / static_cast<float>(params.rays) : 1.0f;
    o.irradiance = core::Vec3{partial[0][0] * inv, partial[1][0] * inv, partial[2][0] * inv};
    out[j] = o;
}

}  // namespace

LightMapCudaResult trace_light_map_cuda(const core::SceneView& host, const core::LightMapTraceParams& params,
                                        std::span<const core::LightMapSampleIn> in, std::uint64_t first_index,
                                        std::span<core::LightMapSampleOut> out,
                                        const std::function<void(std::uint64_t)>& progress) {
    PRT_CUDA_CHECK(cudaSetDevice(0));
    LightMapCudaResult result;
    cudaDeviceProp prop{};
    PRT_CUDA_CHECK(cudaGetDeviceProperties(&prop, 0));
    result.device = prop.name;
    DeviceScene scene;
    scene.upload(host, nullptr);
    const std::uint64_t total = in.size();
    const bool splats_only = (core::scene_mask(host) & ~std::uint32_t{core::k_mask_sampling}) ==
                             std::uint32_t{core::k_mask_splats};
    const std::uint64_t chunk =
        std::min<std::uint64_t>(k_samples_per_launch, std::max<std::uint64_t>(total, 1));
    DeviceBuffer<core::LightMapSampleIn> d_in(chunk);
    DeviceBuffer<core::LightMapSampleOut> d_out(chunk);
    cudaEvent_t start, stop;
    PRT_CUDA_CHECK(cudaEventCreate(&start));
    PRT_CUDA_CHECK(cudaEventCreate(&stop));
    for (std::uint64_t first = 0; first < total; first += chunk) {
        const std::uint64_t count = std::min(chunk, total - first);
        d_in.upload(in.data() + first, count);
        PRT_CUDA_CHECK(cudaEventRecord(start));
        const LaunchShape shape = launch_grid(dim3(static_cast<unsigned>(count)), k_block);
        if (splats_only)
            launch_kernel(shape, light_map_kernel<core::k_mask_splats>, scene.view(), params, d_in.data(),
                          d_out.data(), first_index + first);
        else
            launch_kernel(shape, light_map_kernel<core::k_mask_all>, scene.view(), params, d_in.data(),
                          d_out.data(), first_index + first);
        PRT_CUDA_CHECK(cudaEventRecord(stop));
        PRT_CUDA_CHECK(cudaEventSynchronize(stop));
        float ms = 0.0f;
        PRT_CUDA_CHECK(cudaEventElapsedTime(&ms, start, stop));
        result.kernel_seconds += ms * 1e-3;
        d_out.download(out.data() + first, count);
        PRT_CUDA_CHECK(cudaDeviceSynchronize());
        if (progress) progress(first + count);
    }
    cudaEventDestroy(start);
    cudaEventDestroy(stop);
    return result;
}

}  // namespace prt::cuda
