// PointRT preprocess: what prt-photons (thesis 5.4) and prt-lightmap (thesis 5.3) share: sparse
// octrees whose filled leaves all sit at one level with a value at each leaf corner
// (prt/formats/gi_layout.h), built from samples (photon deposits, light-map samples) in a model's
// local frame, and writing those sections into the scene's pools in place.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "buffer.h"
#include "morton.h"
#include "prt/core/gi.h"
#include "prt/formats/gi_layout.h"
#include "prt/formats/pool.h"
#include "prt/parallel.h"

namespace prt::gi {

/// Sorts keys ascending (LSD radix over the low `bits` bits) and returns the permutation:
/// order[k] = index of the k-th smallest key. Stable. `threads` 0: every hardware thread.
std::vector<std::uint32_t> radix_order(std::span<const std::uint64_t> keys, std::uint32_t bits,
                                       unsigned threads = 0);
/// Sorts and removes duplicates in place (LSD radix over the low `bits` bits).
void sort_unique(std::vector<std::uint64_t>& keys, std::uint32_t bits, unsigned threads = 0);

/// An open-addressing hash map from 64-bit keys to 32-bit values (insert-only, fixed capacity).
class KeyMap {
public:
    explicit KeyMap(std::size_t expected);
    void insert(std::uint64_t key, std::uint32_t value);
    /// Inserts keys[i] -> i for every i, from `threads` workers (compare-and-swap on the slots);
    /// the keys must be distinct. Lookups afterwards answer as after serial inserts.
    void insert_indices(std::span<const std::uint64_t> keys, unsigned threads);
    /// The value of `key`, or k_missing.
    std::uint32_t find(std::uint64_t key) const;
    static constexpr std::uint32_t k_missing = 0xffffffffu;

private:
    std::vector<std::uint64_t> m_keys;  // key + 1; 0 = empty slot
    std::vector<std::uint32_t> m_values;
    std::uint64_t m_mask = 0;
};

/// Points binned into the cells of one octree level: the sample indices sorted by cell (Morton
/// order), each occupied cell's range of them, and a hash from cell key to cell.
struct CellBins {
    std::uint32_t depth = 0;
    double root_min[3] = {0, 0, 0};
    double root_size = 1.0;
    pre::Buffer<std::uint32_t> order;       ///< sample indices grouped by cell
    std::vector<std::uint64_t> cell_keys;   ///< Morton key per occupied cell, ascending
    std::vector<std::uint32_t> cell_begin;  ///< per occupied cell + 1: range into `order`
    KeyMap map{1};                          ///< cell key -> index into cell_keys

    double edge() const { return root_size / static_cast<double>(1ull << depth); }
    /// Continuous cell coordinates of a local point (cell i spans [i, i + 1)).
    void grid(const float p[3], double g[3]) const;
    /// Integer cell of a local point, clamped into the root.
    void cell_of(const float p[3], std::uint32_t c[3]) const;
};

/// Bins `count` points (positions p(i), local frame) at `depth` under the root cube, from
/// `threads` workers (0: every hardware thread; the result does not depend on it). Without
/// `with_map`, CellBins::map stays empty (for callers that find cells otherwise).
template <class PositionOf>
CellBins bin_points(std::size_t count, const double root_min[3], double root_size, std::uint32_t depth,
                    PositionOf position_of, unsigned threads = 0, bool with_map = true);
CellBins bin_keys(pre::Buffer<std::uint64_t> keys, const double root_min[3], double root_size,
                  std::uint32_t depth, unsigned threads = 0, bool with_map = true);

template <class PositionOf>
CellBins bin_points(std::size_t count, const double root_min[3], double root_size, std::uint32_t depth,
                    PositionOf position_of, unsigned threads, bool with_map) {
    CellBins probe;
    probe.depth = depth;
    probe.root_size = root_size;
    for (int a = 0; a < 3; ++a) probe.root_min[a] = root_min[a];
    pre::Buffer<std::uint64_t> keys(count);
    parallel_chunks(count, 1 << 16, resolve_threads(threads),
                    [&](std::size_t begin, std::size_t end, unsigned) {
                        for (std::size_t i = begin; i < end; ++i) {
                            std::uint32_t c[3];
                            probe.cell_of(position_of(i), c);
                            keys[i] = pre::morton3(c[0], c[1], c[2]);
                        }
                    });
    return bin_keys(std::move(keys), root_min, root_size, depth, threads, with_map);
}

/// A built GI octree: info, node words and leaves, ready for the pool.
struct GiOctree {
    pool::GiInfo info{};
    std::vector<std::uint32_t> nodes;
    std::vector<pool::GiLeaf> leaves;
};

/// One filled leaf before encoding: its cell (Morton key at the leaf level), 8 linear RGB corner
/// values and its normal (zero: none).
struct LeafValues {
    std::uint64_t key;
    float corner[8][3];
    float normal[3];
};

/// Builds the node words (breadth first, children in Morton order, pool_layout.h) and the encoded
/// leaves of an octree whose filled leaves are `leaves` (sorted by key, unique) at `depth`; picks
/// GiInfo::scale so the largest corner value is representable and fills root, depth and counts.
/// Throws prt::Error when the tree would need more than 2^30 nodes. `threads`: as bin_points.
GiOctree build_octree(const std::vector<LeafValues>& leaves, const double root_min[3], double root_size,
                      std::uint32_t depth, unsigned threads = 0);

/// The node words of build_octree for filled leaves at the cells `keys` (Morton keys at `depth`,
/// sorted, unique); leaf j's word addresses leaf j. Level by level, each level in parallel: the
/// same words whatever the thread count. Throws prt::Error past 2^30 nodes.
std::vector<std::uint32_t> build_nodes(std::span<const std::uint64_t> keys, std::uint32_t depth,
                                       unsigned threads = 0);

/// GiInfo::scale for a map whose largest finite corner value is `max_value` (>= 0): the largest
/// value maps below RGB9E5's maximum.
float map_scale(float max_value);
/// One encoded corner (value / scale, RGB9E5) and one encoded normal component (x 127).
std::uint32_t encode_corner(const float value[3], float scale);
std::int8_t encode_normal(float n);
/// Fills t.info's root, depth, counts (from t.nodes and t.leaves) and scale.
void fill_info(GiOctree& t, const double root_min[3], double root_size, std::uint32_t depth, float scale);

/// The core's view of a built tree (pointers into `t`), as a loaded pool gives it.
core::GiOctreeView view_of(const GiOctree& t);

/// The model's splat-octree root cube (local frame): the GI octrees use it as their root.
void splat_root(const pool::PoolFile& pool, double root_min[3], double& root_size, std::uint32_t& depth);

/// The three sections of one GI map in a pool.
struct GiSectionTypes {
    pool::SectionType info, nodes, leaves;
};
inline constexpr GiSectionTypes k_caustic_sections{
    pool::SectionType::caustic_info, pool::SectionType::caustic_nodes, pool::SectionType::caustic_leaves};
inline constexpr GiSectionTypes k_light_map_sections{pool::SectionType::light_map_info,
                                                     pool::SectionType::light_map_nodes,
                                                     pool::SectionType::light_map_leaves};

/// Rewrites the pool at `path` in place, atomically (pool::PoolWriter: temporary file + rename):
/// every other section carried over, the map's three sections replaced by `tree` or removed when
/// `tree` is null, and {tool, version, parameters} appended to the provenance.
void write_gi_pool(const std::filesystem::path& path, const GiSectionTypes& types, const GiOctree* tree,
                   const std::string& tool, const std::string& parameters_json);

/// The same with any number of maps (issue 20: a caustic map per placement of the pool, each
/// GiInfo::placement set): their infos in one section, their nodes and leaves one after the other
/// (formats/POOL.md); no map removes the sections.
void write_gi_pool(const std::filesystem::path& path, const GiSectionTypes& types,
                   std::span<const GiOctree* const> trees, const std::string& tool,
                   const std::string& parameters_json);

}  // namespace prt::gi
