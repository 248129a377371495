// PointRT preprocess: sparse GI octrees (prt/formats/gi_layout.h) shared by prt-photons and
// prt-lightmap: Morton keys, radix sorting, cell binning, node building and in-place pool writes.
#include "gi_build.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "iso_morton.h"
#include "parallel.h"
#include "prt/core/gi.h"
#include "prt/error.h"

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

constexpr std::uint32_t k_digit_bits = 11;

}  // namespace

// The interleaving of prt-iso's codes (iso_morton.h), so both trees order children alike.
std::uint64_t morton3(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return iso::detail::morton3(x, y, z);
}

void demorton3(std::uint64_t key, std::uint32_t& x, std::uint32_t& y, std::uint32_t& z) {
    x = iso::detail::compact21(key);
    y = iso::detail::compact21(key >> 1);
    z = iso::detail::compact21(key >> 2);
}

namespace {

/// Stable LSD radix sort of `keys` (and `values` alongside, when not null) over the low `bits`
/// bits, 11 bits per pass; each pass counts and scatters contiguous blocks in parallel.
void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>* values, std::uint32_t bits) {
    const std::size_t n = keys.size();
    constexpr std::size_t k_buckets = std::size_t{1} << k_digit_bits;
    const unsigned threads = static_cast<unsigned>(
        std::min<std::size_t>(pre::resolve_threads(0), std::max<std::size_t>(1, n >> 16)));
    const std::size_t block = (n + threads - 1) / std::max(1u, threads);
    std::vector<std::uint64_t> tmp_keys(n);
    std::vector<std::uint32_t> tmp_values(values ? n : 0);
    std::vector<std::size_t> count(threads * k_buckets);
    const std::uint64_t mask = k_buckets - 1;
    for (std::uint32_t shift = 0; shift < bits; shift += k_digit_bits) {
        std::fill(count.begin(), count.end(), 0);
        pre::parallel_chunks(n, block, threads, [&](std::size_t begin, std::size_t end, unsigned) {
            std::size_t* c = &count[(begin / block) * k_buckets];
            for (std::size_t i = begin; i < end; ++i) ++c[(keys[i] >> shift) & mask];
        });
        std::size_t sum = 0;  // bucket-major, block-minor: stable
        for (std::size_t d = 0; d < k_buckets; ++d)
            for (unsigned t = 0; t < threads; ++t) {
                const std::size_t v = count[t * k_buckets + d];
                count[t * k_buckets + d] = sum;
                sum += v;
            }
        pre::parallel_chunks(n, block, threads, [&](std::size_t begin, std::size_t end, unsigned) {
            std::size_t* c = &count[(begin / block) * k_buckets];
            for (std::size_t i = begin; i < end; ++i) {
                const std::size_t at = c[(keys[i] >> shift) & mask]++;
                tmp_keys[at] = keys[i];
                if (values) tmp_values[at] = (*values)[i];
            }
        });
        keys.swap(tmp_keys);
        if (values) values->swap(tmp_values);
    }
}

}  // namespace

std::vector<std::uint32_t> radix_order(std::span<const std::uint64_t> keys, std::uint32_t bits) {
    std::vector<std::uint64_t> k(keys.begin(), keys.end());
    std::vector<std::uint32_t> order(keys.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    radix_sort(k, &order, bits);
    return order;
}

void sort_unique(std::vector<std::uint64_t>& keys, std::uint32_t bits) {
    radix_sort(keys, nullptr, bits);
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

CellBins bin_keys(std::vector<std::uint64_t> keys, const double root_min[3], double root_size,
                  std::uint32_t depth) {
    CellBins b;
    b.depth = depth;
    b.root_size = root_size;
    for (int a = 0; a < 3; ++a) b.root_min[a] = root_min[a];
    b.order = radix_order(keys, 3 * depth);
    for (std::size_t k = 0; k < b.order.size(); ++k) {
        const std::uint64_t key = keys[b.order[k]];
        if (b.cell_keys.empty() || b.cell_keys.back() != key) {
            b.cell_keys.push_back(key);
            b.cell_begin.push_back(static_cast<std::uint32_t>(k));
        }
    }
    b.cell_begin.push_back(static_cast<std::uint32_t>(b.order.size()));
    b.map = KeyMap(b.cell_keys.size());
    for (std::size_t c = 0; c < b.cell_keys.size(); ++c)
        b.map.insert(b.cell_keys[c], static_cast<std::uint32_t>(c));
    return b;
}

GiOctree build_octree(const std::vector<LeafValues>& leaves, const double root_min[3], double root_size,
                      std::uint32_t depth) {
    if (depth > pool::k_max_gi_depth)
        throw Error("GI octree depth " + std::to_string(depth) + " above the limit " +
                    std::to_string(pool::k_max_gi_depth));
    GiOctree t;
    // Distinct prefixes per level (the internal nodes), from the sorted leaf keys, each level from
    // the one below it.
    std::vector<std::vector<std::uint64_t>> prefixes(depth + 1);
    prefixes[depth].reserve(leaves.size());
    for (const LeafValues& lv : leaves) prefixes[depth].push_back(lv.key);
    for (std::uint32_t l = depth; l-- > 0;) {
        for (std::uint64_t k : prefixes[l + 1]) {
            const std::uint64_t p = k >> 3;
            if (prefixes[l].empty() || prefixes[l].back() != p) prefixes[l].push_back(p);
        }
    }
    std::uint64_t node_count = 1;
    for (std::uint32_t l = 0; l < depth; ++l) node_count += 8ull * prefixes[l].size();
    if (leaves.empty()) node_count = 1;
    if (node_count > pool::k_node_address_max)
        throw Error("GI octree needs " + std::to_string(node_count) + " nodes, more than 2^30");
    t.nodes.assign(node_count, pool::make_node(pool::NodeType::empty_leaf, 0));
    if (!leaves.empty()) {
        if (depth == 0) {
            t.nodes[0] = pool::make_node(pool::NodeType::filled_leaf, 0);
        } else {
            // Breadth first: level l's internal nodes (prefixes[l], in order) own consecutive
            // groups of 8 slots at level l + 1; slot[j] is where prefixes[l][j]'s node word sits.
            std::vector<std::uint64_t> slot{0}, next_slot;
            std::uint64_t next_base = 1;
            for (std::uint32_t l = 0; l < depth; ++l) {
                const std::vector<std::uint64_t>& here = prefixes[l];
                const std::vector<std::uint64_t>& below = prefixes[l + 1];
                next_slot.assign(below.size(), 0);
                std::size_t j = 0;  // position in `below`
                for (std::size_t i = 0; i < here.size(); ++i) {
                    const std::uint64_t first = next_base + 8 * i;
                    t.nodes[slot[i]] =
                        pool::make_node(pool::NodeType::internal, static_cast<std::uint32_t>(first));
                    for (; j < below.size() && (below[j] >> 3) == here[i]; ++j) {
                        next_slot[j] = first + (below[j] & 7u);
                        if (l + 1 == depth)
                            t.nodes[next_slot[j]] =
                                pool::make_node(pool::NodeType::filled_leaf, static_cast<std::uint32_t>(j));
                    }
                }
                slot.swap(next_slot);
                next_base += 8 * here.size();
            }
        }
    }
    // Encode the leaves with one scale for the map (the largest value maps below RGB9E5's maximum).
    float max_value = 0.0f;
    for (const LeafValues& lv : leaves)
        for (const auto& c : lv.corner)
            for (float v : c)
                if (std::isfinite(v)) max_value = std::max(max_value, v);
    const float scale = max_value > 0.0f ? max_value / 32768.0f : 1.0f;
    t.leaves.resize(leaves.size());
    for (std::size_t i = 0; i < leaves.size(); ++i) {
        pool::GiLeaf& out = t.leaves[i];
        for (int c = 0; c < 8; ++c)
            out.corner[c] =
                core::encode_rgb9e5(core::Vec3{leaves[i].corner[c][0] / scale, leaves[i].corner[c][1] / scale,
                                               leaves[i].corner[c][2] / scale});
        for (int a = 0; a < 3; ++a)
            out.normal[a] =
                static_cast<std::int8_t>(std::lround(std::clamp(leaves[i].normal[a], -1.0f, 1.0f) * 127.0f));
        out.reserved = 0;
    }
    for (int a = 0; a < 3; ++a) t.info.root_min[a] = static_cast<float>(root_min[a]);
    t.info.root_size = static_cast<float>(root_size);
    t.info.depth = depth;
    t.info.node_count = static_cast<std::uint32_t>(t.nodes.size());
    t.info.leaf_count = static_cast<std::uint32_t>(t.leaves.size());
    t.info.scale = scale;
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
    const pool::PoolFile in = pool::PoolFile::open(path);
    pool::PoolWriter w;
    w.carry_over(in);
    w.remove(types.info);
    w.remove(types.nodes);
    w.remove(types.leaves);
    if (tree != nullptr) {
        w.add_array(types.info, std::vector<pool::GiInfo>{tree->info});
        w.add_array(types.nodes, tree->nodes);
        w.add_array(types.leaves, tree->leaves);
    }
    w.add_provenance(tool, PRT_VERSION, parameters_json);
    w.write(path);
}

}  // namespace prt::gi
