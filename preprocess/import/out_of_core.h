// PointRT prt-import out of core (issue 17, prt-import --memory): one PLY, XYZ or pool point set larger
// than the memory allowed, streamed and worked tile by tile, with the result of the in-core import
// (import_file) bit for bit:
//
//   file --chunks--> decimate, drop non-finite / zero normals (clean()) --> spill files
//   exact duplicates: hash buckets of at most --memory each (the same hash and first-kept rule as clean())
//   outliers: the statistics of outliers_and_graph() over tiled_knn() (tiled_knn.h), medians by
//             a two-pass radix selection (exact)
//   normals: pca_normals_tiled() in the float frame of the in-core KdTree, oriented toward the
//            sensor point by point (orient_toward_one), then clean()'s check of the normals
//   pool: positions, normals, colors, radii, intensities as views of the spill files, streamed
//         by PoolWriter::write().
//
// Every per-point array lives in a spill file (spill_file.h); what stays in memory is a chunk of the
// input, a bucket of duplicate keys or a tile of the k-NN search, each within --memory.
// Merged scans (--poses) go the same way scan by scan, then are concatenated and finished as
// import_merged() does (import_merged_out_of_core).
// Pools of one scan are read the same way (read_point_sections() in chunks).
// Normals without a sensor: propagation over the whole k-NN graph with every array in spill files
// (orient_over_rows; semi-external: the files advised random, their pages dropped every 4096
// vertices; the resident set is reclaimable file pages, a few times --memory between drops).
// Not out of core (estimate_import says why, one line): meshes, PCD, pools of several scans,
// grazing normals whose edges do not fit in half the memory.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "import.h"
#include "orient.h"
#include "spill_file.h"

namespace prt::pool {
class PoolFile;
class PoolWriter;
}  // namespace prt::pool

namespace prt::pre::import {

/// --keep-fraction's choice: whether the point at `index` (in file order) is kept. A counter-based
/// hash of (seed, index) (splitmix64's finalizer): the same points for the same file and seed.
inline bool decimation_keeps(std::uint64_t index, double fraction, std::uint64_t seed) {
    std::uint64_t h = seed * 0x9E3779B97F4A7C15ull + index;
    h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
    h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
    h ^= h >> 31;
    return double(h >> 11) * 0x1.0p-53 < fraction;
}

/// --memory, --spill-folder and the hidden --tile-points of prt-import.
struct MemoryParams {
    std::uint64_t memory = 1ull << 30;   ///< bytes the import may hold
    std::filesystem::path spill_folder;  ///< where the spill files go (empty: the current folder)
    std::uint64_t tile_points = 0;       ///< > 0: out of core whatever the size, tiles of this many points
};

/// What the in-core import of one input would hold, and whether the out-of-core one can take it.
struct ImportEstimate {
    std::uint64_t points = 0;  ///< PLY: the vertex count; XYZ: the line count; others: file size / 12
    std::uint64_t bytes = 0;   ///< the in-core import's working set, about
    /// Why the out-of-core import cannot take this input with these options, naming the option or
    /// the file ("" when it can).
    std::string unsupported;
};

/// Estimates the in-core import of `path` (single input, no pose list) from its header or size.
/// Throws prt::Error for a file that cannot be opened.
/// `sensor_given`: a pose list gives the scan a sensor.
ImportEstimate estimate_import(const std::filesystem::path& path, const Options& options,
                               bool sensor_given = false);

/// A per-point array in a spill file.
template <class T>
struct SpillArray {
    std::shared_ptr<SpillFile> file;
    std::span<T> span() const { return file ? file->as<T>() : std::span<T>{}; }
};

/// The result of the out-of-core import: the point sections in spill files (`size` points each).
struct SpilledCloud {
    std::uint64_t size = 0;
    SpillArray<std::array<double, 3>> positions;
    SpillArray<pool::Float3> normals;  ///< empty file when none
    SpillArray<pool::Rgba8> colors;
    SpillArray<float> radii;
    SpillArray<float> intensities;
    SpillArray<std::uint16_t> scan_ids;  ///< merged scans with a sensor each: index into sensors
    std::vector<pool::Sensor> sensors;
    std::uint32_t flags = 0;
};

/// import_file() out of core for a PLY, XYZ or one-scan pool point set (estimate_import().unsupported empty):
/// the same points, attributes, order, counts in `report` (timings aside), within memory.memory.
/// Throws prt::Error as import_file() does, and for inputs estimate_import() does not support.
SpilledCloud import_file_out_of_core(const std::filesystem::path& path, const Options& options,
                                     const MemoryParams& memory, Report& report);

/// import_merged() out of core: every scan of the pose list (or of `only`) a PLY or XYZ point set,
/// each read, cleaned and rid of outliers in its own frame out of core, moved, merged in the same
/// order, then duplicates across scans and normals as import_merged() does them (toward each
/// point's own sensor; estimated normals need sensors). Throws prt::Error as import_merged() does,
/// and for scans or options the out-of-core import does not support.
SpilledCloud import_merged_out_of_core(const std::filesystem::path& poses,
                                       const std::vector<std::filesystem::path>& only, const Options& options,
                                       const MemoryParams& memory, Report& report);

/// write_point_sections() for a SpilledCloud: the sections are views of its spill files (the
/// writer keeps them alive), the positions' local float copy another spill file.
void write_point_sections(const SpilledCloud& cloud, const MemoryParams& memory, pool::PoolWriter& writer);

/// One entry of the k-NN graph's adjacency lists that the --grazing-cos propagation follows out of
/// core: `target` (a grazing point) in the list of the point key >> 32, put there when the row of
/// point key & 0xFFFFFFFF was read, at rank j (the order orient_by_propagation() builds its lists in).
struct GrazingEdge {
    std::uint64_t key;
    std::uint32_t j;
    std::uint32_t target;
};

/// Appends the entries of point g's k-NN row (k_no_neighbour where short) that end at a grazing
/// point; state[i]: 0 no valid normal (no part), 1 fixed (a source), 2 grazing.
void add_grazing_edges(std::uint32_t g, const std::uint32_t* row, std::uint32_t k,
                       std::span<const std::uint8_t> state, std::vector<GrazingEdge>& edges);

/// orient_by_propagation() with the points of state 1 fixed, over the edges add_grazing_edges()
/// collected from every row: the same steps (propagate_signs), so the grazing normals (state 2)
/// get the signs the in-core run gives them; height_of(i) is point i's z. Calls too_big() (which
/// throws) when the vertices and edges need more than `memory` bytes. Returns the flips.
std::uint64_t propagate_grazing(std::vector<GrazingEdge> edges, std::span<const std::uint8_t> state,
                                std::span<pool::Float3> normals,
                                const std::function<double(std::uint32_t)>& height_of, std::uint64_t memory,
                                const std::function<void()>& too_big, bool quiet);

/// orient_by_propagation() out of core over a k-NN graph given as rows (rows[i * k + j], n =
/// normals.size() points; a spill file when large): the symmetric adjacency lists built in two
/// passes in point order as orient_by_propagation() builds them, and propagate_signs() with its
/// per-point arrays, all in spill files in `spill_folder` (about 8k + 33 bytes per point); `fixed`
/// (may be empty) the sources, height(i) point i's z. `drop()` is called between passes (the caller
/// drops its mappings' pages). The same signs and counts as orient_by_propagation().
OrientStats orient_over_rows(std::span<const std::uint32_t> rows, std::uint32_t k,
                             std::span<pool::Float3> normals, std::span<const std::uint8_t> fixed,
                             const std::function<double(std::uint32_t)>& height,
                             const std::filesystem::path& spill_folder, const std::function<void()>& drop,
                             bool quiet);

/// The notes, counts and sensor source of a pool input (import.cpp's and the out-of-core reader's).
void pool_input_report(const pool::PoolFile& file, const std::filesystem::path& path, Report& report);

/// The median as median_of() in neighbours.cpp takes it (the element of rank (n - 1) / 2) of n
/// non-negative floats given by `value(i)`, read twice in index order (two 16-bit radix passes).
float median_streamed(std::uint64_t n, const std::function<float(std::uint64_t)>& value);

}  // namespace prt::pre::import
