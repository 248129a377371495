// PointRT preprocess: the brick builder (issue 17). Cuts a splat octree (prt-octree, prt-cull) into
// a small resident top tree and bricks (subtrees of at most N splats, replicas counted), compresses
// each brick's splats to 12 bytes (codec in formats/include/prt/formats/brick_layout.h) and computes
// a level-of-detail disc per top node and per node of each brick's top levels. Produces exactly the
// pool sections brick_info, brick_top_nodes, brick_table, brick_data, lod_splats (and brick_lod,
// lod_nodes).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "octree_build.h"
#include "prt/formats/brick_layout.h"
#include "prt/formats/octree_sections.h"
#include "prt/formats/pool.h"

namespace prt::pre {

struct BrickParams {
    /// N: a node whose subtree holds at most N stored splats (replicas counted) becomes a brick,
    /// cutting greedily from the root. 8192 (12 B each: 96 KiB of splats per brick; a 500M-point
    /// room gets about 121,000 bricks): streamed under a budget of an eighth of the pool, that room's
    /// 100-frame orbit converged in 89 of 100 frames with these bricks, 46 with 32768 (the default
    /// on 2026-11-28, which had made its close view converge where 131072 held only 430 of the 949
    /// bricks it needed): a ray wants a brick whole for the part it passes near. Models that fit
    /// trace 1.7-2.3 % slower with them than with 32768; uploads still run at 3-3.5 GB/s (H200,
    /// 2026-11-29, preprocess/bench/results/h200-2026-11-29-issue17-cones).
    std::uint32_t brick_splats = 8192;
    /// M of each brick's level-of-detail prefix (sections brick_lod, lod_nodes): the brick's top
    /// levels down to the deepest whose non-empty nodes hold at least M splat references on average,
    /// each node with a compressed disc. 0: no prefix (a ray then stops only at top nodes).
    std::uint32_t lod_splats = 32;
    /// Direct bricks (brick_layout.h): a brick stores its leaves' splats in leaf order, a replica
    /// once per leaf, with no references, so a splat test makes one dependent read instead of two.
    /// smaller: where that takes no more bytes than references (little replication: culled pools);
    /// always; never.
    enum class Direct { smaller, always, never };
    Direct direct = Direct::smaller;
    unsigned threads = 0;  ///< worker threads; 0 = every hardware thread
    /// Progress of the encoding, called from the calling thread with (bricks done, bricks); may be empty.
    std::function<void(std::uint64_t, std::uint64_t)> progress;
};

/// The codec's error over every stored splat, measured against the float splats while encoding.
struct CodecError {
    std::uint64_t splats = 0;
    double position_max = 0, position_sum = 0;  ///< |decoded - float centre| / float radius
    double position_quanta_max = 0;             ///< largest per-axis error in quanta of its brick's cube
    double normal_max_deg = 0, normal_sum_deg = 0;
    double radius_growth_max = 0, radius_growth_sum = 0;  ///< decoded / float radius - 1 (>= 0)
    double radius_shrink_max = 0;                         ///< 1 - decoded / float where smaller: 0
    std::uint32_t color_max = 0;                          ///< largest channel error, 0..255
    std::uint64_t radii_raised = 0;  ///< radii below the brick's smallest code (grew more than one step)
    void merge(const CodecError& o);
};

struct BrickStats {
    std::uint32_t bricks = 0, top_nodes = 0, top_depth = 0;
    std::uint32_t min_brick_splats = 0, max_brick_splats = 0;
    std::uint64_t splats = 0, data_bytes = 0;
    std::uint64_t encoded =
        0;  ///< compressed splats (each splat once per brick; per reference in direct bricks)
    std::uint32_t direct_bricks = 0;  ///< bricks stored direct (BrickParams::direct)
    std::uint64_t lod_nodes =
        0;  ///< nodes of the bricks' LOD prefixes (16 B each with their discs, resident when streaming)
    CodecError error;
    double seconds = 0;
};

/// The brick sections, ready to be added to a pool (add_brick_sections()).
struct BrickedOctree {
    pool::BrickInfo info{};
    std::vector<std::uint32_t> top_nodes;
    std::vector<pool::BrickEntry> table;
    std::vector<std::byte> data;
    std::vector<pool::LodSplat> lod;
    std::vector<pool::BrickLod> lod_table;  ///< per brick (BrickParams::lod_splats > 0), else empty
    std::vector<std::uint32_t> lod_nodes;
    std::vector<pool::CompressedSplat> lod_discs;  ///< parallel to lod_nodes
};

/// Builds the bricks of `octree`; `colors` (per point, may be empty: white) gives the splats'
/// colours through Splat::point. Throws prt::Error on an octree the format cannot hold (a splat
/// count above 2^32 - 1 in one brick, a radius the codec cannot represent).
BrickedOctree build_bricks(const pool::SplatOctreeSections& octree, std::span<const pool::Rgba8> colors,
                           const BrickParams& params, BrickStats* stats = nullptr);

// ---- The pieces of build_bricks, for the out-of-core build (bricks_from_points.h) --------------

/// Area-weighted sums of a node's points (LOD): each point once, in the leaf whose half-open cell
/// holds its centre (BrickEncoder::encode in brick_build.cpp).
struct LodSum {
    double w = 0, p[3] = {0, 0, 0}, n[3] = {0, 0, 0}, c[3] = {0, 0, 0};
    void add(const LodSum& o) {
        w += o.w;
        for (int a = 0; a < 3; ++a) p[a] += o.p[a], n[a] += o.n[a], c[a] += o.c[a];
    }
    /// A point of weight `wt` (its disc's area) at `pos` with unit normal `nrm` and colour `col`.
    void add_point(double wt, const double pos[3], const double nrm[3], const double col[3]) {
        w += wt;
        for (int a = 0; a < 3; ++a) p[a] += wt * pos[a], n[a] += wt * nrm[a], c[a] += wt * col[a];
    }
};

/// The bricks of one node's subtree: `bricks` as build_bricks makes them but numbered from that
/// node (top node 0 is `root`; table offsets into bricks.data; BrickEntry::top_node local), the
/// internal top nodes' discs not yet made, brick_info empty; `sums` per top node (each brick's at
/// its top node).
struct BrickPart {
    BrickedOctree bricks;
    std::vector<LodSum> sums;
    std::uint32_t top_depth = 0;
    CodecError error;
};

/// Phases 1-3 of build_bricks over `octree`, whose node 0 is node `root` of the whole octree
/// (octree.info holds the whole octree's root cube). Every ancestor of `root` must be an internal
/// top node of the whole octree's cut (its subtree holds more than BrickParams::brick_splats).
BrickPart build_brick_part(const pool::SplatOctreeSections& octree, std::span<const pool::Rgba8> colors,
                           const BrickParams& params, NodeCell root);

/// Phase 4 and brick_info over a whole top tree: the internal top nodes' discs from `sums`, then
/// brick_info from `octree_info` (root cube, depth, flags, unique splats) and the table. Returns the
/// statistics but data_bytes, error and seconds.
BrickStats finish_bricks(BrickedOctree& out, std::vector<LodSum>& sums, const pool::OctreeInfo& octree_info,
                         std::uint32_t top_depth, const BrickParams& params, bool colors);

/// Adds (replacing) the brick sections to a writer (five, eight with the LOD prefixes).
void add_brick_sections(BrickedOctree bricks, pool::PoolWriter& writer);
/// The same but brick_data (bricks.data is ignored: the caller adds brick_data, e.g. from a spill file).
void add_brick_index_sections(BrickedOctree bricks, pool::PoolWriter& writer);

}  // namespace prt::pre
