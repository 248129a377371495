// PointRT CUDA: leaf bounds of streamed bricks on the GPU (brick_bounds.h). Never include PCL,
// OpenMesh or OpenImageIO here.
#include <cuda_runtime.h>

#include "brick_bounds.h"
#include "cuda_check.h"
#include "prt/core/bricks.h"
#include "prt/core/leaf_bounds.h"

namespace prt::cuda {

namespace {

constexpr unsigned k_bounds_block = 128;

__global__ void brick_bounds_kernel(const BrickBoundsJob* jobs, std::uint32_t job_count,
                                    std::uint32_t leaves) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= leaves) return;
    std::uint32_t lo = 0, hi = job_count - 1;  // the last job whose first leaf is <= i
    while (lo < hi) {
        const std::uint32_t mid = (lo + hi + 1) / 2;
        if (jobs[mid].first_leaf <= i)
            lo = mid;
        else
            hi = mid - 1;
    }
    const BrickBoundsJob job = jobs[lo];
    const std::uint32_t l = i - job.first_leaf;
    if (l >= job.leaf_count) return;
    const core::BrickSplats src = core::brick_splats(job.payload);
    const std::uint32_t* leaf_info = reinterpret_cast<const std::uint32_t*>(
        job.payload + pool::brick_leaf_info_offset(src.header.node_count));
    // As rt::build_brick_leaf_bounds over the brick's decoded splats: the range clamped as there.
    std::uint32_t e = leaf_info[l + 1] < src.header.splat_count ? leaf_info[l + 1] : src.header.splat_count;
    std::uint32_t b = leaf_info[l] < e ? leaf_info[l] : e;
    const core::BrickLeafBounds out = core::brick_leaf_bounds_of(src, b, e);
    job.bounds[l] = out;
}

}  // namespace

void derive_brick_leaf_bounds(const BrickBoundsJob* jobs, std::uint32_t job_count, std::uint32_t leaves,
                              cudaStream_t stream) {
    if (job_count == 0 || leaves == 0) return;
    launch_kernel(launch_1d(leaves, k_bounds_block, stream), brick_bounds_kernel, jobs, job_count, leaves);
}

}  // namespace prt::cuda
