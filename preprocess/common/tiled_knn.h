// PointRT preprocess: exact k nearest neighbours of a point set larger than the memory allowed, tile
// by tile with a halo (issue 17: out-of-core prt-radii and prt-import normals). Shared by the tools
// that need k-NN over every point; the k-NN itself is the one kd-tree of the project (kd_tree.h).
//
// How (and why the result equals one kd-tree over all points, bit for bit):
//  1. Tiles: a kd partition of space (median splits along the widest axis, Friedman, Bentley &
//     Finkel 1977) computed on a regular sample of the points, with as many leaves as needed for a
//     tile to hold about `tile_points` points. Every point falls in exactly one tile (a point on a
//     split plane goes to the upper side).
//  2. Bucketing: one counting pass and one scatter pass over the positions write (x, y, z, index)
//     records into a spill file sorted by tile, in index order within a tile.
//  3. Round 1, per tile: a kd-tree over the tile's points alone. A point whose k-th distance d is
//     (with a float margin) smaller than its distance to the tile's border has the same k nearest
//     neighbours as over all points: every point outside is farther than the border.
//  4. Round 2, the others: d above is an upper bound of the true k-th distance, so every true
//     neighbour lies within d of the point, hence inside the tile's box grown by h = max d. The tile
//     plus that halo (read from the neighbouring tiles' records) is gathered and searched; when the
//     halo would exceed the memory, the points are split by d and done in smaller groups, and a
//     point whose own halo is still too big (an isolated outlier), or a run of a few points, is
//     searched by a streaming scan (scans run in parallel).
//  Ties: the kd-tree orders equally distant points by index; every gathered set is kept in index
//  order, so local index order equals global order and the same tie-break picks the same points.
//  Distances are computed the same way (dx * dx + dy * dy + dz * dz in float, d = point - query).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>

#include "prt/formats/pool_layout.h"

namespace prt::pre {

struct TiledKnnParams {
    std::uint32_t k = 9;
    unsigned threads = 0;                ///< 0 = every hardware thread
    std::uint64_t memory = 1ull << 30;   ///< bytes the search may hold (tile, halo, kd-tree, results)
    std::uint64_t tile_points = 0;       ///< points per tile; 0 = from `memory` (tests force small tiles)
    std::filesystem::path spill_folder;  ///< where the sorted records go (empty: the current folder)
    /// The positions are a read-only file mapping (a pool's section): drop_pages() them after each
    /// pass so the resident set stays bounded. Never set it for positions in anonymous memory (a
    /// vector): dropping those pages would zero them.
    bool positions_mapped = false;
};

struct TiledKnnStats {
    std::uint64_t points = 0;
    std::uint64_t tiles = 0;
    std::uint64_t tile_points = 0;   ///< the target points per tile
    std::uint64_t halo_queries = 0;  ///< points that needed a halo (round 2)
    std::uint64_t halo_groups = 0;   ///< gathered sets searched in round 2
    std::uint64_t scanned = 0;       ///< points searched by a streaming scan (halo over the memory)
    std::uint64_t max_gathered = 0;  ///< the largest set held at once
    std::uint64_t gathered = 0;      ///< points gathered by round 2's groups, in all
    /// The largest anonymous resident memory (RssAnon: heap, not the mapped files the kernel can
    /// reclaim) seen when a batch was complete, the moment the search holds the most.
    std::uint64_t peak_anon_rss = 0;
    double seconds_bucket = 0, seconds_search = 0;
};

/// A set of points whose k nearest neighbours are final. Local indices are into `points`/`global`.
struct KnnBatch {
    std::span<const pool::Float3> points;       ///< the gathered points, by increasing global index
    std::span<const std::uint32_t> global;      ///< their indices in the whole point set
    std::span<const std::uint32_t> queries;     ///< local indices of the points done in this batch
    std::span<const std::uint32_t> neighbours;  ///< queries.size() x k local indices, nearest first
    std::span<const float> distance2;           ///< the squared distances, same layout
};

/// Working bytes per gathered point (records, kd-tree, results) that TiledKnnParams::memory is
/// divided by.
std::uint64_t tiled_knn_bytes_per_point(std::uint32_t k);

/// Exact k nearest other points of every point (as KdTree<float>::for_each over all of them:
/// coincident points count at distance 0, ties by index), tile by tile within params.memory.
/// `visit` is called from the calling thread once per batch; every point is a query of exactly
/// one batch. `progress(done)` counts points done. Throws prt::Error for <= k points, more than
/// 2^32 - 1 points or a non-finite position (naming the point).
void tiled_knn(std::span<const pool::Float3> positions, const TiledKnnParams& params,
               const std::function<void(const KnnBatch&)>& visit,
               const std::function<void(std::uint64_t)>& progress = {}, TiledKnnStats* stats = nullptr);

}  // namespace prt::pre
