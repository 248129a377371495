// PointRT CUDA: prt-cull's per-leaf culling (thesis 3.4) on a caller's stream over device memory
// (runtime/cuda/src/cull.cu). Shared by cull_leaves_cuda (an octree uploaded from the host) and by
// the splat octree builder (octree_build.cu: a cell of the out-of-core build culled where it was
// built, so its replicated splats never come down to the host). Host-only header.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <functional>

#include "prt/core/cull.h"

namespace prt::cuda {

/// Runs core::cull_leaf() for every filled leaf of `view`, whose arrays are in device memory, on
/// `stream`. `keep` (one flag per stored splat, initialised as cull_leaf() expects) and `votes`
/// (zeroed, one per stored splat; only for the votes policy, else null) are device arrays. With a
/// `progress`, the stream is waited for after each launch and `progress(done, leaves)` called;
/// without one, the launches are only queued. Returns the summed counters (waits for the stream).
core::CullCounters cull_on_stream(const core::CullView& view, std::uint8_t* keep, std::uint32_t* votes,
                                  cudaStream_t stream,
                                  const std::function<void(std::uint64_t, std::uint64_t)>& progress);

}  // namespace prt::cuda
