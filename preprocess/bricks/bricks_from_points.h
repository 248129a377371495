// PointRT preprocess: bricks straight from points, out of core (issue 17). Builds the bricked
// octree that prt-octree -> prt-cull -> prt-bricks would build, equal byte for byte, without ever
// holding the whole splat octree: the model is partitioned into cells of the octree that each fit
// in --memory, and each cell's subtree is built (build_octree_cell), culled (cull_octree over a part)
// and cut into bricks (build_brick_part) alone; the top tree, the brick table and the LOD discs
// above the cells are assembled at the end.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>

#include "brick_build.h"
#include "cull_build.h"
#include "octree_build.h"
#include "prt/formats/pool.h"
#include "spill_file.h"

namespace prt::pre {

struct PointBrickParams {
    OctreeParams octree;  ///< prt-octree's parameters (threads, progress unused: see below)
    bool cull = true;     ///< probe-ray culling of each cell (prt-cull, thesis 3.4)
    CullParams culling;   ///< prt-cull's parameters
    BrickParams bricks;   ///< prt-bricks' parameters
    /// Memory for one cell's build; the partition makes cells of about memory /
    /// k_cell_bytes_per_point points.
    std::uint64_t memory = std::uint64_t(4) << 30;
    /// > 0: cells of at most about this many points whatever the memory (tests, benchmarks).
    std::uint64_t cell_points = 0;
    std::filesystem::path spill_folder;  ///< the partitioned points and the brick payloads
    /// The input arrays are a file mapping (a pool opened from a file): the passes over them unmap
    /// the pages they are done with (spill_file.h drop_pages), so the resident set stays bounded.
    /// Never true for arrays in anonymous memory (dropping would zero them).
    bool input_mapped = false;
    /// With input_mapped: the radii are part of a file mapping too (the input's section or a spill
    /// file); false when they are anonymous memory (computed in the process), whose pages are kept.
    bool radii_mapped = true;
    unsigned threads = 0;  ///< 0 = every hardware thread
    /// Cells built at the same time, each with threads / cell_workers threads; --memory is shared
    /// among them (cells of memory / (cell_workers x k_cell_bytes_per_point) points). 0: one per
    /// thread, each cell on one thread (fastest measured on 16 threads: 4, 8, 16 at once on a 200M
    /// room). The result does not depend on it.
    unsigned cell_workers = 0;
    /// Progress on stderr: (stage, done, total), called from one thread at a time (the cell workers
    /// take turns); may be empty.
    std::function<void(const char*, std::uint64_t, std::uint64_t)> progress;
};

/// Bytes one cell's build holds per point of the cell (points, build records, the replicated and the
/// culled octree, the cell's bricks). Measured: peak 9.71 GiB for cells of up to 12.6M points
/// (826 B per point, a 100M-point room, H100 host, 16 threads); 7.8 stored replicas per point
/// before culling make most of it.
inline constexpr std::uint64_t k_cell_bytes_per_point = 840;

/// The cells built at once (PointBrickParams::cell_workers resolved) and the most points a cell is
/// planned to hold (cell_points, else memory / (cell workers x k_cell_bytes_per_point), at least 65536).
unsigned cell_workers(const PointBrickParams& params);
std::uint64_t cell_capacity(const PointBrickParams& params);

struct PointBrickStats {
    std::uint64_t points = 0, skipped = 0;  ///< usable points; points the octree skips
    std::uint32_t cells = 0;                ///< cells built (non-empty)
    /// of those, cells built and culled on the GPU in one pass (cull_build.h, build_culled_cell):
    /// their culling time is in octree_seconds
    std::uint32_t cells_culled_on_device = 0;
    std::uint32_t partition_depth = 0;      ///< deepest cell level
    std::uint64_t cell_records = 0;  ///< points over all cells (a point in several cells counts in each)
    std::uint64_t max_cell_points = 0;
    std::uint64_t stored_splats = 0, culled_splats = 0;  ///< replicated octree; after culling
    BrickStats bricks;
    double seconds = 0;
    /// Where the time went: passes over the points (bounds, histogram, count, scatter), the cells'
    /// octree builds, culling, brick cuts, the cuts' payloads written to the spill or part file, and
    /// the assembly (the cells' times summed over the workers).
    double partition_seconds = 0, octree_seconds = 0, cull_seconds = 0, brick_seconds = 0,
           payload_write_seconds = 0, assemble_seconds = 0;
    /// partition_seconds by pass: bounds, histogram (with the partition), count, scatter.
    std::array<double, 4> partition_pass_seconds{};
};

/// The brick sections; brick_data (`data_bytes` long) is not gathered anywhere: `data` hands it to a
/// sink front to back (the payloads in table order, each padded to pool::k_brick_alignment with
/// zeros), reading the cells' payloads from the spill or part files it holds, as the pool is written
/// (pool::PoolWriter::add_generated). It may be called more than once; it reports "writing bricks"
/// through the build's PointBrickParams::progress, which must outlive it (null: none).
struct PointBricks {
    BrickedOctree bricks;  ///< data empty
    pool::PoolWriter::Generator data;
    std::uint64_t data_bytes = 0;
};

/// Builds the bricks of the points (positions, normals, radii, colours may be empty) within
/// `params.memory`. Throws prt::Error when no point is usable, or when the model cannot be
/// partitioned (a cell that must be split holds too few points to be an inner top node).
PointBricks build_bricks_from_points(std::span<const pool::Float3> positions,
                                     std::span<const pool::Float3> normals, std::span<const float> radii,
                                     std::span<const pool::Rgba8> colors, const PointBrickParams& params,
                                     PointBrickStats* stats = nullptr);

/// The same build in three stages, for processes on one or several machines that share `folder`
/// (issue 21: scripts/prt-bricks-dask runs the cells on a Dask cluster, the way Entwine builds
/// subsets and merges them). The merged result equals build_bricks_from_points' byte for byte:
/// cells are independent (bricks_from_points.cpp), and culling hashes a leaf's cell, not its index.
///  1. plan_brick_cells: steps 1-5 on the points; writes folder/plan.bin (the partition, the options
///     that change the result) and folder/records.bin (each cell's points, 32 B a record), removes an
///     earlier plan's part files, and returns the number of cells. An earlier plan stays whole until
///     the new one is complete, and its records file is replaced (renamed over), not rewritten, so a
///     process still reading it is not cut short.
///  2. build_brick_cells: cells [first, last) of the plan (built, culled, cut) into
///     folder/cells-FIRST-LAST.bin, written atomically; any number of these, anywhere, in any order.
///  3. merge_brick_cells: the top tree, table, payloads and LOD from part files that cover every cell
///     once (each checked: checksums, ranges).
/// Every stage must get the same `params` but threads, memory and spill folder (a mismatch is an
/// error naming both). Throws prt::Error naming the file on a missing, corrupt or foreign file, and
/// naming the cells that no part holds.
std::uint32_t plan_brick_cells(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                               std::span<const float> radii, std::span<const pool::Rgba8> colors,
                               const PointBrickParams& params, const std::filesystem::path& folder,
                               PointBrickStats* stats = nullptr);
/// The number of cells of folder's plan (checked against `params`).
std::uint32_t planned_brick_cells(const std::filesystem::path& folder, const PointBrickParams& params);
void build_brick_cells(const std::filesystem::path& folder, const PointBrickParams& params,
                       std::uint32_t first, std::uint32_t last, PointBrickStats* stats = nullptr);
PointBricks merge_brick_cells(const std::filesystem::path& folder, const PointBrickParams& params,
                              PointBrickStats* stats = nullptr);

}  // namespace prt::pre
