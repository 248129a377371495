// PointRT preprocess: sparse GI octrees (prt/formats/gi_layout.h) shared by prt-photons and
// prt-lightmap: cell binning over Morton keys (morton.h, radix_sort.h), node building and in-place pool
// writes.
#include "gi_build.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "prt/core/gi.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "radix_sort.h"

namespace prt::gi {

namespace {

std::uint64_t mix64(std::uint64_t x) {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdull;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ull;
    x ^= x >> 33;
    return x;
}

}  // namespace

std::vector<std::uint32_t> radix_order(std::span<const std::uint64_t> keys, std::uint32_t bits,
                                       unsigned threads) {
    std::vector<std::uint64_t> k(keys.begin(), keys.end());
    std::vector<std::uint32_t> order(keys.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    pre::radix_sort(k, &order, bits, threads);
    return order;
}

void sort_unique(std::vector<std::uint64_t>& keys, std::uint32_t bits, unsigned threads) {
    pre::radix_sort_by(keys, bits, threads, [](std::uint64_t k) { return k; });
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

KeyMap::KeyMap(std::size_t expected) {
    std::size_t cap = 16;
    while (cap < expected * 2) cap <<= 1;
    m_keys.assign(cap, 0);
    m_values.assign(cap, k_missing);
    m_mask = cap - 1;
}

void KeyMap::insert(std::uint64_t key, std::uint32_t value) {
    for (std::uint64_t h = mix64(key) & m_mask;; h = (h + 1) & m_mask) {
        if (m_keys[h] == 0 || m_keys[h] == key + 1) {
            m_keys[h] = key + 1;
            m_values[h] = value;
            return;
        }
    }
}

void KeyMap::insert_indices(std::span<const std::uint64_t> keys, unsigned threads) {
    parallel_chunks(keys.size(), 1 << 14, resolve_threads(threads),
                    [&](std::size_t begin, std::size_t end, unsigned) {
                        for (std::size_t i = begin; i < end; ++i) {
                            const std::uint64_t want = keys[i] + 1;
                            for (std::uint64_t h = mix64(keys[i]) & m_mask;; h = (h + 1) & m_mask) {
                                std::uint64_t seen = 0;
                                std::atomic_ref<std::uint64_t> slot(m_keys[h]);
                                if (slot.load(std::memory_order_relaxed) == 0 &&
                                    slot.compare_exchange_strong(seen, want, std::memory_order_relaxed)) {
                                    m_values[h] = static_cast<std::uint32_t>(i);
                                    break;
                                }
                            }
                        }
                    });
}

std::uint32_t KeyMap::find(std::uint64_t key) const {
    for (std::uint64_t h = mix64(key) & m_mask;; h = (h + 1) & m_mask) {
        if (m_keys[h] == key + 1) return m_values[h];
        if (m_keys[h] == 0) return k_missing;
    }
}

void CellBins::grid(const float p[3], double g[3]) const {
    const double cells = static_cast<double>(1ull << depth);
    for (int a = 0; a < 3; ++a) g[a] = (static_cast<double>(p[a]) - root_min[a]) / root_size * cells;
}

void CellBins::cell_of(const float p[3], std::uint32_t c[3]) const {
    double g[3];
    grid(p, g);
    const double last = static_cast<double>((1ull << depth) - 1);
    for (int a = 0; a < 3; ++a) {
        const double v = std::isfinite(g[a]) ? std::clamp(std::floor(g[a]), 0.0, last) : 0.0;
        c[a] = static_cast<std::uint32_t>(v);
    }
}

CellBins bin_keys(pre::Buffer<std::uint64_t> keys, const double root_min[3], double root_size,
                  std::uint32_t depth, unsigned threads, bool with_map) {
    threads = resolve_threads(threads);
    CellBins b;
    b.depth = depth;
    b.root_size = root_size;
    for (int a = 0; a < 3; ++a) b.root_min[a] = root_min[a];
    const std::size_t n = keys.size();
    b.order = pre::Buffer<std::uint32_t>(n);
    parallel_chunks(n, 1 << 16, threads, [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) b.order[i] = static_cast<std::uint32_t>(i);
    });
    pre::radix_sort(keys, &b.order, 3 * depth, threads);  // keys now sorted
    // The occupied cells: where the sorted key changes (parallel compaction, order kept).
    auto starts = [&](std::size_t k) { return k == 0 || keys[k] != keys[k - 1]; };
    const std::size_t cells = parallel_select(n, threads, starts, [](std::size_t, std::size_t) {});
    b.cell_keys.resize(cells);
    b.cell_begin.resize(cells + 1);
    parallel_select(n, threads, starts, [&](std::size_t rank, std::size_t k) {
        b.cell_keys[rank] = keys[k];
        b.cell_begin[rank] = static_cast<std::uint32_t>(k);
    });
    b.cell_begin[cells] = static_cast<std::uint32_t>(n);
    if (with_map) {
        b.map = KeyMap(b.cell_keys.size());
        b.map.insert_indices(b.cell_keys, threads);
    }
    return b;
}

std::vector<std::uint32_t> build_nodes(std::span<const std::uint64_t> keys, std::uint32_t depth,
                                       unsigned threads) {
    if (depth > pool::k_max_gi_depth)
        throw Error("GI octree depth " + std::to_string(depth) + " above the limit " +
                    std::to_string(pool::k_max_gi_depth));
    threads = resolve_threads(threads);
    if (keys.empty()) return {pool::make_node(pool::NodeType::empty_leaf, 0)};
    if (depth == 0) return {pool::make_node(pool::NodeType::filled_leaf, 0)};
    // prefixes[l]: the distinct key prefixes at level l (the internal nodes there, l < depth), from
    // the level below by parallel compaction; parent[l][j]: the index in prefixes[l - 1] of
    // prefixes[l][j]'s parent (its rank among the compacted prefixes).
    std::vector<std::vector<std::uint64_t>> prefixes(depth);
    std::vector<std::vector<std::uint32_t>> parent(depth + 1);
    for (std::uint32_t l = depth; l-- > 0;) {
        const std::span<const std::uint64_t> below =
            l + 1 == depth ? keys : std::span<const std::uint64_t>(prefixes[l + 1]);
        std::vector<std::uint32_t>& up = parent[l + 1];
        up.resize(below.size());
        auto starts = [&](std::size_t k) { return k == 0 || (below[k] >> 3) != (below[k - 1] >> 3); };
        const std::size_t count =
            parallel_select(below.size(), threads, starts, [](std::size_t, std::size_t) {});
        prefixes[l].resize(count);
        parallel_select(below.size(), threads, starts,
                        [&](std::size_t rank, std::size_t k) { prefixes[l][rank] = below[k] >> 3; });
        // Ranks of every element: the compaction rank of its run's start.
        parallel_chunks(below.size(), 1 << 15, threads, [&](std::size_t begin, std::size_t end, unsigned) {
            // Rank at `begin`: the first prefix >= below[begin] >> 3 (prefixes[l] is sorted).
            const std::uint64_t p0 = below[begin] >> 3;
            std::size_t r = static_cast<std::size_t>(
                std::lower_bound(prefixes[l].begin(), prefixes[l].end(), p0) - prefixes[l].begin());
            for (std::size_t k = begin; k < end; ++k) {
                if (k > begin && starts(k)) ++r;
                up[k] = static_cast<std::uint32_t>(r);
            }
        });
    }
    // Breadth first: level l's nodes (l >= 1) fill 8 slots per internal node of level l - 1, from
    // base[l]; prefixes[l - 1][i] owns slots base[l] + 8 i .. + 7.
    std::vector<std::uint64_t> base(depth + 2, 0);
    base[1] = 1;
    for (std::uint32_t l = 1; l <= depth; ++l) base[l + 1] = base[l] + 8ull * prefixes[l - 1].size();
    const std::uint64_t node_count = base[depth + 1];
    if (node_count > pool::k_node_address_max)
        throw Error("GI octree needs " + std::to_string(node_count) + " nodes, more than 2^30");
    std::vector<std::uint32_t> nodes(node_count, pool::make_node(pool::NodeType::empty_leaf, 0));
    nodes[0] = pool::make_node(pool::NodeType::internal, 1);
    for (std::uint32_t l = 1; l <= depth; ++l) {
        const std::span<const std::uint64_t> here =
            l == depth ? keys : std::span<const std::uint64_t>(prefixes[l]);
        const std::vector<std::uint32_t>& up = parent[l];
        parallel_chunks(here.size(), 1 << 15, threads, [&](std::size_t begin, std::size_t end, unsigned) {
            for (std::size_t j = begin; j < end; ++j) {
                const std::uint64_t slot = base[l] + 8ull * up[j] + (here[j] & 7u);
                nodes[slot] =
                    l == depth ? pool::make_node(pool::NodeType::filled_leaf, static_cast<std::uint32_t>(j))
                               : pool::make_node(pool::NodeType::internal,
                                                 static_cast<std::uint32_t>(base[l + 1] + 8ull * j));
            }
        });
    }
    return nodes;
}

float map_scale(float max_value) {
    return max_value > 0.0f ? max_value / 32768.0f : 1.0f;
}

std::uint32_t encode_corner(const float value[3], float scale) {
    return core::encode_rgb9e5(core::Vec3{value[0] / scale, value[1] / scale, value[2] / scale});
}

std::int8_t encode_normal(float n) {
    return static_cast<std::int8_t>(std::lround(std::clamp(n, -1.0f, 1.0f) * 127.0f));
}

void fill_info(GiOctree& t, const double root_min[3], double root_size, std::uint32_t depth, float scale) {
    for (int a = 0; a < 3; ++a) t.info.root_min[a] = static_cast<float>(root_min[a]);
    t.info.root_size = static_cast<float>(root_size);
    t.info.depth = depth;
    t.info.node_count = static_cast<std::uint32_t>(t.nodes.size());
    t.info.leaf_count = static_cast<std::uint32_t>(t.leaves.size());
    t.info.scale = scale;
}

GiOctree build_octree(const std::vector<LeafValues>& leaves, const double root_min[3], double root_size,
                      std::uint32_t depth, unsigned threads) {
    threads = resolve_threads(threads);
    GiOctree t;
    std::vector<std::uint64_t> keys(leaves.size());
    for (std::size_t i = 0; i < leaves.size(); ++i) keys[i] = leaves[i].key;
    t.nodes = build_nodes(keys, depth, threads);
    // One scale for the map: the largest finite corner value (a maximum: any order gives it).
    constexpr std::size_t k_chunk = 1 << 14;
    std::vector<float> chunk_max((leaves.size() + k_chunk - 1) / k_chunk, 0.0f);
    parallel_chunks(leaves.size(), k_chunk, threads, [&](std::size_t begin, std::size_t end, unsigned) {
        float m = 0.0f;
        for (std::size_t i = begin; i < end; ++i)
            for (const auto& c : leaves[i].corner)
                for (float v : c)
                    if (std::isfinite(v)) m = std::max(m, v);
        chunk_max[begin / k_chunk] = m;
    });
    float max_value = 0.0f;
    for (float m : chunk_max) max_value = std::max(max_value, m);
    const float scale = map_scale(max_value);
    t.leaves.resize(leaves.size());
    parallel_chunks(leaves.size(), k_chunk, threads, [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) {
            pool::GiLeaf& out = t.leaves[i];
            for (int c = 0; c < 8; ++c) out.corner[c] = encode_corner(leaves[i].corner[c], scale);
            for (int a = 0; a < 3; ++a) out.normal[a] = encode_normal(leaves[i].normal[a]);
            out.reserved = 0;
        }
    });
    fill_info(t, root_min, root_size, depth, scale);
    return t;
}

core::GiOctreeView view_of(const GiOctree& t) {
    core::GiOctreeView v;
    v.nodes = t.nodes.data();
    v.node_count = static_cast<std::uint32_t>(t.nodes.size());
    v.leaves = t.leaves.data();
    v.leaf_count = static_cast<std::uint32_t>(t.leaves.size());
    v.depth = t.info.depth;
    v.root_min = core::Vec3{t.info.root_min[0], t.info.root_min[1], t.info.root_min[2]};
    v.root_size = t.info.root_size;
    v.inv_root_size = 1.0f / t.info.root_size;
    v.scale = t.info.scale;
    v.cos_threshold = t.info.cos_threshold;
    return v;
}

void splat_root(const pool::PoolFile& pool, double root_min[3], double& root_size, std::uint32_t& depth) {
    const auto info =
        pool.require<pool::OctreeInfo>(pool::SectionType::octree_info, "the GI octrees (run prt-octree)");
    if (info.size() != 1)
        pool.fail(pool.find(pool::SectionType::octree_info), "must hold exactly one element");
    for (int a = 0; a < 3; ++a) root_min[a] = info[0].root_min[a];
    root_size = info[0].root_size;
    depth = info[0].depth;
}

void write_gi_pool(const std::filesystem::path& path, const GiSectionTypes& types, const GiOctree* tree,
                   const std::string& tool, const std::string& parameters_json) {
    const GiOctree* const one[1] = {tree};
    write_gi_pool(path, types, std::span<const GiOctree* const>(one, tree != nullptr ? 1 : 0), tool,
                  parameters_json);
}

void write_gi_pool(const std::filesystem::path& path, const GiSectionTypes& types,
                   std::span<const GiOctree* const> trees, const std::string& tool,
                   const std::string& parameters_json) {
    const pool::PoolFile in = pool::PoolFile::open(path);
    pool::PoolWriter w;
    w.carry_over(in);
    w.remove(types.info);
    w.remove(types.nodes);
    w.remove(types.leaves);
    if (!trees.empty()) {
        std::vector<pool::GiInfo> infos;
        std::vector<std::uint32_t> nodes;
        std::vector<pool::GiLeaf> leaves;
        for (const GiOctree* t : trees) {
            infos.push_back(t->info);
            nodes.insert(nodes.end(), t->nodes.begin(), t->nodes.end());
            leaves.insert(leaves.end(), t->leaves.begin(), t->leaves.end());
        }
        w.add_array(types.info, infos);
        w.add_array(types.nodes, nodes);
        w.add_array(types.leaves, leaves);
    }
    w.add_provenance(tool, PRT_VERSION, parameters_json);
    w.write(path);
}

}  // namespace prt::gi
