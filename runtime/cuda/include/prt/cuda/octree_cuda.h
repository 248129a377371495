// PointRT CUDA: the splat octree builder's GPU path (thesis 2.2, 3.2, 3.4): the subtree below one
// node (the whole octree's root, or one cell of an out-of-core build) built level by level on the
// device, deciding every split and every child with the functions the CPU builder runs
// (core/disk_box.h; compiled without FMA contraction), so the sections are byte-identical to
// preprocess/splat/octree_build.h's. Plain C++ header (no CUDA types), so octree_build.cpp, compiled
// by g++, calls it (prt/cuda/device.h says whether a device is there). Implemented in
// runtime/cuda/src/octree_build.cu (target prt_octree_cuda).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "prt/core/cull.h"
#include "prt/core/disk_box.h"
#include "prt/formats/pool_layout.h"

namespace prt::cuda {

/// The builder's rules (preprocess/splat/octree_build.h, OctreeParams).
struct OctreeCudaParams {
    std::uint32_t max_leaf_splats = 48;
    std::uint32_t max_depth = 24;
    bool replicate = true;
    float min_cell_ratio = 0.25f;
    bool split_by_centres = false;
};

/// The built subtree: node words breadth first (node 0 = the start node, children of a node
/// contiguous), filled leaves numbered and their splats stored depth first, each leaf's splats whose
/// centre lies in its closed box first; the counts build_octree reports.
struct OctreeCudaResult {
    std::vector<std::uint32_t> nodes;
    std::vector<std::uint32_t> leaf_info;  ///< filled leaves + 1
    std::vector<pool::Splat> splats;
    std::uint32_t depth = 0;  ///< the deepest leaf's level in the whole octree's numbering
    std::uint64_t empty_leaves = 0;
    std::uint64_t max_leaf = 0;  ///< most splats in one leaf
    /// Splats stored before culling (build_cull_octree_cuda); splats.size() otherwise.
    std::uint64_t stored = 0;
    /// build_cull_octree_cuda: the usable points (the build records made on the device).
    std::uint64_t usable = 0;
};

/// One cell's points as the out-of-core build gathers them (any points: those the builder skips,
/// preprocess/splat/octree_build.h's octree_uses_point, are skipped here too).
struct CellPoints {
    std::span<const pool::Float3> positions;
    std::span<const pool::Float3> normals;
    std::span<const float> radii;
};

/// Builds the subtree below node (level, cell) of the octree whose root cube is (root_min,
/// root_size), over `splats` (usable points, in the order the CPU builder lists them: Morton order
/// of the centres), on device 0. `check(nodes, filled_leaves, stored)` is called with the sizes
/// before the result is allocated (it throws to refuse them). Throws prt::Error on a CUDA error.
void build_octree_cuda(std::span<const core::BuildSplat> splats, const float root_min[3], float root_size,
                       std::uint32_t level, const std::uint32_t cell[3], const OctreeCudaParams& params,
                       const std::function<void(std::uint64_t, std::uint64_t, std::uint64_t)>& check,
                       OctreeCudaResult& out);

/// build_octree_cuda over the build records of `points` made on the device (the usable points,
/// core::make_build_splat, in the CPU builder's Morton order; out.usable gets how many), then the
/// subtree culled on the device (thesis 3.4; runtime/cuda/src/cull.cu,
/// the per-leaf function prt-cull runs) and its kept splats compacted there, so the replicated
/// splats (several per point) never come down to the host: the out-of-core brick build's cells
/// (issue 17). `probes` gives the probes' settings (directions in host memory, their sets, grid,
/// policy, window, seed; its octree and leaves are ignored). `out` gets the node words (unchanged
/// by culling), the culled leaf ranges and splats, as preprocess/splat/cull_build.h's cull_octree
/// gives them over OctreePart{(level, cell)}; out.stored the splats stored before culling. `counters` (if
/// given) gets culling's counters. Requires params.replicate. Throws prt::Error on a CUDA error.
void build_cull_octree_cuda(const CellPoints& points, const float root_min[3], float root_size,
                            std::uint32_t level, const std::uint32_t cell[3], const OctreeCudaParams& params,
                            const core::CullView& probes,
                            const std::function<void(std::uint64_t, std::uint64_t, std::uint64_t)>& check,
                            OctreeCudaResult& out, core::CullCounters* counters = nullptr);

}  // namespace prt::cuda
