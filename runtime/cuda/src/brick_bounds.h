// PointRT CUDA: leaf bounds of streamed bricks derived on the GPU (issue 17): after a brick's
// payload reaches the device arena, one thread per filled leaf computes its core::BrickLeafBounds from
// the payload (prt/core/leaf_bounds.h, the host's arithmetic) into the brick's bounds block, so the
// host only checks and copies.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "prt/core/octree.h"

namespace prt::cuda {

/// One uploaded brick: its payload and bounds block in device memory, its filled leaves, and the
/// index of its first leaf among the batch's leaves (jobs sorted by it, the first at 0).
struct BrickBoundsJob {
    const unsigned char* payload;
    core::BrickLeafBounds* bounds;
    std::uint32_t first_leaf;
    std::uint32_t leaf_count;
};

/// Derives the bounds of every leaf of `job_count` jobs (`jobs` in device memory, `leaves` leaves in
/// all) on `stream`, after the work queued there before (the payload copies).
void derive_brick_leaf_bounds(const BrickBoundsJob* jobs, std::uint32_t job_count, std::uint32_t leaves,
                              cudaStream_t stream);

}  // namespace prt::cuda
