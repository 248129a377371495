// PointRT CUDA: prt-lightmap's kernel (thesis 5.3). One thread traces one light-map sample with
// core::trace_light_map_sample(), the function the CPU path runs, over the device copy of the scene
// (DeviceScene, shared with the renderer and prt-photons), so both give the same irradiance up to
// floating-point rounding (tests/preprocess/lightmap/lightmap_gpu_test.cpp). Samples go up in
// launches of k_samples_per_launch, so progress is reported between them.
#include <cuda_runtime.h>

#include <algorithm>

#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/cuda/device.h"
#include "prt/cuda/device_scene.h"
#include "prt/cuda/lightmap_cuda.h"

namespace prt::cuda {

namespace {

constexpr std::uint32_t k_block = 128;
/// Samples per launch: each traces `rays` paths, so a launch is a few tens of milliseconds.
constexpr std::uint64_t k_samples_per_launch = 1ull << 16;

__global__ void __launch_bounds__(k_block)
    light_map_kernel(const core::SceneView scene, const core::LightMapTraceParams params,
                     const core::LightMapSampleIn* in, core::LightMapSampleOut* out, std::uint64_t count,
                     std::uint64_t first_index) {
    const std::uint64_t i = static_cast<std::uint64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= count) return;
    core::RayCounters c;
    out[i] = core::trace_light_map_sample(scene, params, in[i], first_index + i, c);
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
        launch_kernel(launch_1d(count, k_block), light_map_kernel, scene.view(), params, d_in.data(),
                      d_out.data(), count, first_index + first);
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
