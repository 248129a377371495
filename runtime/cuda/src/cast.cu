// PointRT CUDA backend: ray batches (issue 18; Backend::cast / Backend::occluded): one thread per
// ray over the core's cast_one / occluded_one (prt/core/cast.h), the same functions the CPU backend
// runs. Device arrays are read and written in place; host arrays go through device copies.
// Never include PCL, OpenMesh or OpenImageIO here.
#include <cuda_runtime.h>

#include <chrono>
#include <cstring>

#include "cast_batch.h"
#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/core/cast.h"

namespace prt::cuda {

namespace {

constexpr std::uint32_t k_cast_block = 256;

/// Closest hits: splat scenes get a kernel without the other surfaces' code (as the megakernel's
/// splat variant), everything else the general one. 4 blocks per SM: unlike the megakernel's splat
/// variants (3 since 2026-12-06), the splat cast kernel at 3 was slower (H100, 10M random rays from
/// a sphere of radius 3, on the device: kernel 14.2 -> 15.7 ms on the culled 1M sphere, 16.6 -> 17.1
/// on the culled room, 21.1 -> 24.1 on the culled 10M sphere;
/// preprocess/bench/results/h100-2026-12-06-issue19-occupancy, e3.txt).
template <std::uint32_t K>
__global__ void __launch_bounds__(k_cast_block, 4)
    cast_kernel(const core::SceneView scene, const core::CastRays rays, const core::CastOutputs out) {
    const std::size_t i = static_cast<std::size_t>(blockIdx.x) * k_cast_block + threadIdx.x;
    if (i >= rays.count) return;
    core::RayCounters c;
    core::cast_one<K>(scene, rays, out, i, c);
}

template <std::uint32_t K>
__global__ void __launch_bounds__(k_cast_block, 4)
    occluded_kernel(const core::SceneView scene, const core::CastRays rays, std::uint8_t* flags,
                    std::uint8_t* valid) {
    const std::size_t i = static_cast<std::size_t>(blockIdx.x) * k_cast_block + threadIdx.x;
    if (i >= rays.count) return;
    core::RayCounters c;
    core::occluded_one<K>(scene, rays, flags, valid, i, c);
}

/// Bytes an array of `count` records `stride` bytes apart, each `record` bytes, spans.
std::size_t span_bytes(std::size_t count, std::size_t stride, std::size_t record) {
    return count == 0 ? 0 : (count - 1) * stride + record;
}

core::CastRays stage_rays(const core::CastRays& rays, CastStaging& s, cudaStream_t stream) {
    core::CastRays d = rays;
    const std::size_t n = rays.count;
    const std::size_t osz = rays.origins_f64 ? 24 : 12, dsz = rays.directions_f64 ? 24 : 12;
    s.origins.upload(static_cast<const unsigned char*>(rays.origins), span_bytes(n, rays.origin_stride, osz),
                     stream);
    s.directions.upload(static_cast<const unsigned char*>(rays.directions),
                        span_bytes(n, rays.direction_stride, dsz), stream);
    d.origins = s.origins.data();
    d.directions = s.directions.data();
    if (rays.t_min) {
        s.t_min.upload(reinterpret_cast<const unsigned char*>(rays.t_min),
                       span_bytes(n, rays.t_min_stride, 4), stream);
        d.t_min = reinterpret_cast<const float*>(s.t_min.data());
    }
    if (rays.t_max) {
        s.t_max.upload(reinterpret_cast<const unsigned char*>(rays.t_max),
                       span_bytes(n, rays.t_max_stride, 4), stream);
        d.t_max = reinterpret_cast<const float*>(s.t_max.data());
    }
    return d;
}

template <class T>
T* stage_out(T* host, DeviceBuffer<T>& buffer, std::size_t count) {
    if (!host) return nullptr;
    buffer.reserve(count);
    return buffer.data();
}

template <class T>
void fetch_out(T* host, const DeviceBuffer<T>& buffer, std::size_t count, cudaStream_t stream) {
    if (host) buffer.download(host, count, 0, stream);
}

/// The frame of a batch: `stage` (host arrays: copy the rays in, point the outputs at staging
/// buffers), then `launch` timed with the context's events, then `fetch` (host arrays: copy the
/// outputs back); device arrays wait for the device first, as the caller's arrays may have been
/// written on another stream (PyTorch's, CuPy's) that this backend's stream does not follow.
template <class Stage, class Launch, class Fetch>
rt::CastStats timed_batch(const CastContext& ctx, std::size_t n, rt::Memory memory, Stage&& stage,
                          Launch&& launch, Fetch&& fetch) {
    const auto t0 = std::chrono::steady_clock::now();
    rt::CastStats stats;
    stats.rays = n;
    if (n == 0) return stats;
    if (memory == rt::Memory::host)
        stage();
    else
        PRT_CUDA_CHECK(cudaDeviceSynchronize());
    PRT_CUDA_CHECK(cudaEventRecord(ctx.start, ctx.stream));
    launch();
    PRT_CUDA_CHECK(cudaEventRecord(ctx.stop, ctx.stream));
    if (memory == rt::Memory::host) fetch();
    PRT_CUDA_CHECK(cudaStreamSynchronize(ctx.stream));
    float ms = 0;
    PRT_CUDA_CHECK(cudaEventElapsedTime(&ms, ctx.start, ctx.stop));
    stats.device_ms = ms;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return stats;
}

}  // namespace

rt::CastStats cast_batch(const CastContext& ctx, const core::CastRays& rays, const core::CastOutputs& out,
                         rt::Memory memory) {
    const bool splats = ctx.surface_mask == core::k_mask_splats;
    CastStaging& s = *ctx.staging;
    core::CastRays d = rays;
    core::CastOutputs o = out;
    const std::size_t n = rays.count;
    return timed_batch(
        ctx, n, memory,
        [&] {
            d = stage_rays(rays, s, ctx.stream);
            o.hit = stage_out(out.hit, s.hit, n);
            o.valid = stage_out(out.valid, s.valid, n);
            o.t = stage_out(out.t, s.t, n);
            o.position = stage_out(out.position, s.position, n * 3);
            o.normal = stage_out(out.normal, s.normal, n * 3);
            o.color = stage_out(out.color, s.color, n * 3);
            o.model = stage_out(out.model, s.model, n);
            o.element = stage_out(out.element, s.element, n);
        },
        [&] {
            launch_kernel(launch_1d(n, k_cast_block, ctx.stream),
                          splats ? cast_kernel<core::k_mask_splats> : cast_kernel<core::k_mask_all>,
                          ctx.scene, d, o);
        },
        [&] {
            fetch_out(out.hit, s.hit, n, ctx.stream);
            fetch_out(out.valid, s.valid, n, ctx.stream);
            fetch_out(out.t, s.t, n, ctx.stream);
            fetch_out(out.position, s.position, n * 3, ctx.stream);
            fetch_out(out.normal, s.normal, n * 3, ctx.stream);
            fetch_out(out.color, s.color, n * 3, ctx.stream);
            fetch_out(out.model, s.model, n, ctx.stream);
            fetch_out(out.element, s.element, n, ctx.stream);
        });
}

rt::CastStats occluded_batch(const CastContext& ctx, const core::CastRays& rays, std::uint8_t* flags,
                             std::uint8_t* valid, rt::Memory memory) {
    const bool splats = ctx.surface_mask == core::k_mask_splats;
    CastStaging& s = *ctx.staging;
    core::CastRays d = rays;
    std::uint8_t *f = flags, *v = valid;
    const std::size_t n = rays.count;
    return timed_batch(
        ctx, n, memory,
        [&] {
            d = stage_rays(rays, s, ctx.stream);
            f = stage_out(flags, s.hit, n);
            v = stage_out(valid, s.valid, n);
        },
        [&] {
            launch_kernel(launch_1d(n, k_cast_block, ctx.stream),
                          splats ? occluded_kernel<core::k_mask_splats> : occluded_kernel<core::k_mask_all>,
                          ctx.scene, d, f, v);
        },
        [&] {
            fetch_out(flags, s.hit, n, ctx.stream);
            fetch_out(valid, s.valid, n, ctx.stream);
        });
}

}  // namespace prt::cuda
