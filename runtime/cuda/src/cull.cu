// PointRT CUDA: prt-cull's kernels (thesis 3.4). One thread culls one filled leaf with
// core::cull_leaf(), the function the CPU path runs: probes are generated from the same host-made
// direction table and integer hashes, walked with the renderer's core::walk_next() and tested
// with core::intersect_splat(). This file is compiled without FMA contraction and without fast
// math (runtime/CMakeLists.txt), so the probes and their hits are bit-identical to the CPU's and
// the two backends keep the same replicas.
//
// Why one thread per leaf: the greedy policy is sequential within a leaf (each probe sees the
// replicas kept by the probes before it), and a 1M-point model has 1-3 x 10^5 filled leaves, about
// as many threads as an H100 holds. Leaves are launched in chunks so that progress can be reported.
#include <cuda_runtime.h>

#include <algorithm>
#include <vector>

#include "cuda_check.h"
#include "cull_device.h"
#include "device_buffer.h"
#include "prt/cuda/cull_cuda.h"
#include "prt/cuda/device.h"

namespace prt::cuda {

namespace {

constexpr std::uint32_t k_block = 128;
/// Leaves per launch: ~2 waves of resident threads on an H100 (132 SMs x 2048), so a launch fills
/// the GPU; progress is reported between launches.
constexpr std::uint32_t k_leaves_per_launch = 1u << 19;

enum CullCounter : std::uint32_t { k_c_probes, k_c_hit, k_c_unserved, k_c_tests, k_c_count };

__global__ void cull_kernel(const core::CullView view, std::uint32_t first, std::uint32_t count,
                            std::uint8_t* keep, std::uint32_t* votes, unsigned long long* counters) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= count) return;
    core::CullCounters c;
    core::cull_leaf(view, first + i, keep, votes, c);
    if (c.probes) atomicAdd(&counters[k_c_probes], static_cast<unsigned long long>(c.probes));
    if (c.probes_hit) atomicAdd(&counters[k_c_hit], static_cast<unsigned long long>(c.probes_hit));
    if (c.probes_unserved)
        atomicAdd(&counters[k_c_unserved], static_cast<unsigned long long>(c.probes_unserved));
    if (c.splat_tests) atomicAdd(&counters[k_c_tests], static_cast<unsigned long long>(c.splat_tests));
}

__global__ void hole_kernel(const core::OctreeView full, const core::OctreeView culled,
                            const core::HoleRay* rays, std::uint64_t count, const core::BlendOptions blend,
                            std::uint32_t max_steps, core::HoleSample* out) {
    const std::uint64_t i = static_cast<std::uint64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= count) return;
    const core::HoleRay r = rays[i];
    core::HoleSample s;
    core::trace_hole_ray(full, culled, r.o, r.d, r.inside != 0, blend, max_steps, s);
    out[i] = s;
}

template <class T>
DeviceBuffer<T> upload(const T* host, std::size_t count) {
    DeviceBuffer<T> b;
    b.upload(host, count);
    return b;
}

/// The device copies of an octree view's arrays, and the view pointing at them.
struct DeviceOctree {
    DeviceBuffer<std::uint32_t> nodes, leaf_info;
    DeviceBuffer<pool::Splat> splats;
    core::OctreeView view;
    explicit DeviceOctree(const core::OctreeView& host) : view(host) {
        nodes = upload(host.nodes, host.node_count);
        leaf_info = upload(host.leaf_info, std::size_t(host.filled_leaves) + 1);
        splats = upload(host.splats, host.splat_count);
        view.nodes = nodes.data();
        view.leaf_info = leaf_info.data();
        view.splats = splats.data();
    }
};

}  // namespace

core::CullCounters cull_on_stream(const core::CullView& view, std::uint8_t* keep, std::uint32_t* votes,
                                  cudaStream_t st,
                                  const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    const std::uint32_t leaves = view.octree.filled_leaves;
    AsyncBuffer<unsigned long long> d_counters(st);
    d_counters.resize(k_c_count);
    PRT_CUDA_CHECK(cudaMemsetAsync(d_counters.data(), 0, d_counters.bytes(), st));
    for (std::uint32_t first = 0; first < leaves; first += k_leaves_per_launch) {
        const std::uint32_t count = std::min(k_leaves_per_launch, leaves - first);
        launch_kernel(launch_1d(count, k_block, st), cull_kernel, view, first, count, keep, votes,
                      d_counters.data());
        if (progress) {
            PRT_CUDA_CHECK(cudaStreamSynchronize(st));
            progress(first + count, leaves);
        }
    }
    unsigned long long c[k_c_count];
    PRT_CUDA_CHECK(cudaMemcpyAsync(c, d_counters.data(), sizeof c, cudaMemcpyDeviceToHost, st));
    PRT_CUDA_CHECK(cudaStreamSynchronize(st));
    core::CullCounters out;
    out.probes = c[k_c_probes];
    out.probes_hit = c[k_c_hit];
    out.probes_unserved = c[k_c_unserved];
    out.splat_tests = c[k_c_tests];
    return out;
}

bool cull_device_available(std::string* why) {
    return device_available(why);
}

std::string cull_device_name() {
    return device_name();
}

core::CullCounters cull_leaves_cuda(const core::CullView& host, std::span<std::uint8_t> keep,
                                    const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    PRT_CUDA_CHECK(cudaSetDevice(0));
    if (keep.size() != host.octree.splat_count)
        throw Error("cull_leaves_cuda: one keep flag per splat expected");
    // A stream and stream-ordered memory of its own: the out-of-core brick build culls its cells
    // from several threads while others build octrees on the GPU (prt/cuda/octree_cuda.h), and a
    // device-wide synchronization or cudaFree here would wait for all of their work.
    keep_pool_memory();
    OwnedStream stream;
    const cudaStream_t st = stream.get();
    const std::uint32_t leaves = host.octree.filled_leaves;
    AsyncBuffer<std::uint32_t> d_nodes(st), d_leaf_info(st);
    AsyncBuffer<pool::Splat> d_splats(st);
    d_nodes.upload(host.octree.nodes, host.octree.node_count);
    d_leaf_info.upload(host.octree.leaf_info, std::size_t(leaves) + 1);
    d_splats.upload(host.octree.splats, host.octree.splat_count);
    AsyncBuffer<core::CullLeaf> d_leaves(st);
    d_leaves.upload(host.leaves, leaves);
    AsyncBuffer<core::ProbeDirection> d_dirs(st);
    d_dirs.upload(host.directions, std::size_t(host.direction_sets) * host.directions_per_set);
    AsyncBuffer<std::uint8_t> d_keep(st);
    d_keep.upload(keep.data(), keep.size());
    AsyncBuffer<std::uint32_t> d_votes(st);
    if (host.policy == core::CullPolicy::votes && !keep.empty()) {
        d_votes.resize(keep.size());
        PRT_CUDA_CHECK(cudaMemsetAsync(d_votes.data(), 0, d_votes.bytes(), st));
    }
    core::CullView view = host;
    view.octree.nodes = d_nodes.data();
    view.octree.leaf_info = d_leaf_info.data();
    view.octree.splats = d_splats.data();
    view.leaves = d_leaves.data();
    view.directions = d_dirs.data();
    const core::CullCounters out = cull_on_stream(view, d_keep.data(), d_votes.data(), st, progress);
    d_keep.download(keep.data(), keep.size());
    PRT_CUDA_CHECK(cudaStreamSynchronize(st));
    return out;
}

void trace_hole_rays_cuda(const core::OctreeView& full, const core::OctreeView& culled,
                          std::span<const core::HoleRay> rays, const core::BlendOptions& blend,
                          std::uint32_t max_steps, std::span<core::HoleSample> out) {
    PRT_CUDA_CHECK(cudaSetDevice(0));
    if (out.size() != rays.size()) throw Error("trace_hole_rays_cuda: one sample per ray expected");
    if (rays.empty()) return;
    DeviceOctree f(full), c(culled);
    DeviceBuffer<core::HoleRay> d_rays = upload(rays.data(), rays.size());
    DeviceBuffer<core::HoleSample> d_out(rays.size());
    launch_kernel(launch_1d(rays.size(), 256), hole_kernel, f.view, c.view, d_rays.data(), rays.size(), blend,
                  max_steps, d_out.data());
    d_out.download(out.data(), out.size());
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
}

}  // namespace prt::cuda
