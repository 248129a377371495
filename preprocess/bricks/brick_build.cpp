// PointRT preprocess: the brick builder (brick_build.h; format in formats/POOL.md, "Bricks and level
// of detail").
//
// 1. Subtree sizes bottom-up over the octree's node array (children are stored after their parent).
// 2. The top tree, breadth first from the root: an empty leaf stays empty; a node holding at most N
//    splats (or a filled leaf, whatever it holds) becomes a brick; any other node stays internal.
// 3. Every brick's splats gathered in parallel: its subtree renumbered breadth first from 0, its
//    filled leaves in the source's leaf order, each distinct splat once (a point's replicas in
//    several leaves of the brick become references to one encoded splat); payload offsets from
//    those counts (each brick 64-byte aligned); then every brick in parallel again: its splats
//    encoded (and the codec's error measured against the float splats), its references, checksum
//    and LOD disc.
//    Each brick's level-of-detail prefix (its top levels, BrickParams::lod_splats) gets a disc per
//    node in the same pass: sums of the points whose centre cell lies below the node, a radius over
//    every splat below it.
// 4. LOD discs of the top tree's internal nodes, bottom-up from their children's discs.
#include "brick_build.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>

#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"

namespace prt::pre {

using pool::NodeType;

namespace {

constexpr double k_pi = 3.14159265358979323846;

float round_up(double x) {
    float f = static_cast<float>(x);
    if (double(f) < x) f = std::nextafter(f, INFINITY);
    return f;
}
float round_down(double x) {
    float f = static_cast<float>(x);
    if (double(f) > x) f = std::nextafter(f, -INFINITY);
    return f;
}

/// The disc of a node from its sums: centre, normal, colour; radius filled in by the caller.
pool::LodSplat lod_from_sum(const LodSum& s) {
    pool::LodSplat d{};
    if (!(s.w > 0)) return d;
    d.position = {float(s.p[0] / s.w), float(s.p[1] / s.w), float(s.p[2] / s.w)};
    const double len = std::sqrt(s.n[0] * s.n[0] + s.n[1] * s.n[1] + s.n[2] * s.n[2]);
    d.normal = len > 1e-12 * s.w ? pool::Float3{float(s.n[0] / len), float(s.n[1] / len), float(s.n[2] / len)}
                                 : pool::Float3{0.0f, 0.0f, 1.0f};
    const auto channel = [&](int a) {
        return static_cast<std::uint8_t>(std::clamp(std::lround(s.c[a] / s.w), 0l, 255l));
    };
    d.color = {channel(0), channel(1), channel(2), 255};
    return d;
}

double distance(const pool::Float3& a, const pool::Float3& b) {
    const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace

void CodecError::merge(const CodecError& o) {
    splats += o.splats;
    position_max = std::max(position_max, o.position_max);
    position_sum += o.position_sum;
    position_quanta_max = std::max(position_quanta_max, o.position_quanta_max);
    normal_max_deg = std::max(normal_max_deg, o.normal_max_deg);
    normal_sum_deg += o.normal_sum_deg;
    radius_growth_max = std::max(radius_growth_max, o.radius_growth_max);
    radius_growth_sum += o.radius_growth_sum;
    radius_shrink_max = std::max(radius_shrink_max, o.radius_shrink_max);
    color_max = std::max(color_max, o.color_max);
    radii_raised += o.radii_raised;
}

namespace {

/// Phase 1: per node, the stored splats, nodes and filled leaves of its subtree.
struct Subtrees {
    std::vector<std::uint64_t> splats;
    std::vector<std::uint32_t> nodes, leaves;
};

Subtrees subtree_sizes(std::span<const std::uint32_t> nodes, std::span<const std::uint32_t> leaf_info) {
    const std::size_t n = nodes.size();
    Subtrees sub{std::vector<std::uint64_t>(n, 0), std::vector<std::uint32_t>(n, 1),
                 std::vector<std::uint32_t>(n, 0)};
    for (std::size_t i = n; i-- > 0;) {  // children are stored after their parent
        const std::uint32_t a = pool::node_address(nodes[i]);
        switch (pool::node_type(nodes[i])) {
            case NodeType::internal:
                for (std::uint32_t c = 0; c < 8; ++c) {
                    sub.splats[i] += sub.splats[a + c];
                    sub.nodes[i] += sub.nodes[a + c];
                    sub.leaves[i] += sub.leaves[a + c];
                }
                break;
            case NodeType::filled_leaf:
                sub.splats[i] = leaf_info[a + 1] - leaf_info[a];
                sub.leaves[i] = 1;
                break;
            default:
                break;
        }
    }
    return sub;
}

/// Phase 2's result: top node t stands for source node src[t] at `level[t]`, integer cell
/// cell[3t..3t+2]; brick b is top node brick_top[b].
struct TopCut {
    std::vector<std::uint32_t> src{0}, level{0}, cell{0, 0, 0};
    std::vector<std::uint32_t> brick_top;
};

/// Phase 2: the top tree, breadth first from the root, into `top_nodes`.
TopCut cut_top_tree(std::span<const std::uint32_t> nodes, const Subtrees& sub, std::uint32_t limit,
                    NodeCell root, std::vector<std::uint32_t>& top_nodes) {
    TopCut cut;
    cut.level[0] = root.level;
    std::copy(root.cell, root.cell + 3, cut.cell.begin());
    for (std::size_t t = 0; t < cut.src.size(); ++t) {
        const std::uint32_t s = cut.src[t];
        const NodeType type = pool::node_type(nodes[s]);
        if (type == NodeType::empty_leaf) {
            top_nodes.push_back(pool::make_node(NodeType::empty_leaf, 0));
        } else if (type == NodeType::filled_leaf || sub.splats[s] <= limit) {
            if (sub.splats[s] > 0xFFFFFFFFull)
                throw Error("a leaf holds " + std::to_string(sub.splats[s]) +
                            " splats; a brick holds at most 2^32 - 1");
            top_nodes.push_back(pool::make_node(NodeType::brick, std::uint32_t(cut.brick_top.size())));
            cut.brick_top.push_back(std::uint32_t(t));
        } else {
            const std::uint32_t first = std::uint32_t(cut.src.size());
            if (std::uint64_t(first) + 8 > pool::k_node_address_max)
                throw Error("the top tree exceeds 2^30 nodes");
            top_nodes.push_back(pool::make_node(NodeType::internal, first));
            const std::uint32_t a = pool::node_address(nodes[s]);
            for (std::uint32_t c = 0; c < 8; ++c) {
                cut.src.push_back(a + c);
                cut.level.push_back(cut.level[t] + 1);
                for (int ax = 0; ax < 3; ++ax) cut.cell.push_back(2 * cut.cell[3 * t + ax] + ((c >> ax) & 1));
            }
        }
    }
    return cut;
}

/// What phase 3a counts of a brick: its compressed splats (distinct, or one per reference when
/// direct) and the nodes of its LOD prefix.
struct BrickCounts {
    std::uint32_t encoded = 0, lod_nodes = 0;
    bool direct = false;
};

/// Whether a brick of `references` splat references to `distinct` distinct splats is stored direct.
bool store_direct(BrickParams::Direct policy, std::size_t references, std::size_t distinct) {
    switch (policy) {
        case BrickParams::Direct::always:
            return true;
        case BrickParams::Direct::never:
            return false;
        default:
            return pool::brick_direct_is_smaller(std::uint32_t(references), std::uint32_t(distinct));
    }
}

/// Phase 3a: each brick's entry (cube, counts, 64-byte aligned payload offset); sizes out.data, and
/// the LOD prefixes' table (first node of each) and nodes when `lod`.
void lay_out_bricks(const TopCut& cut, const Subtrees& sub, const pool::OctreeInfo& oi,
                    const std::vector<BrickCounts>& counts, bool lod, BrickedOctree& out) {
    out.table.resize(cut.brick_top.size());
    if (lod) {
        out.lod_table.assign(cut.brick_top.size(), pool::BrickLod{});
        std::uint64_t first = 0;
        for (std::size_t b = 0; b < counts.size(); ++b) {
            out.lod_table[b].first = first;
            out.lod_table[b].node_count = counts[b].lod_nodes;
            first += counts[b].lod_nodes;
        }
        out.lod_nodes.assign(first, 0);
        out.lod_discs.assign(first, pool::CompressedSplat{});
    }
    std::uint64_t offset = 0;
    for (std::size_t b = 0; b < cut.brick_top.size(); ++b) {
        const std::uint32_t t = cut.brick_top[b];
        const std::uint32_t s = cut.src[t];
        pool::BrickEntry& e = out.table[b];
        const double size = double(oi.root_size) / double(std::uint64_t(1) << cut.level[t]);
        for (int ax = 0; ax < 3; ++ax)
            e.cube_min[ax] = float(double(oi.root_min[ax]) + size * cut.cell[3 * t + ax]);
        e.cube_size = float(size);
        e.offset = offset;
        e.node_count = sub.nodes[s];
        e.leaf_count = sub.leaves[s];
        e.splat_count = std::uint32_t(sub.splats[s]);
        e.encoded_count = counts[b].encoded;
        e.size = pool::brick_payload_size(e.node_count, e.leaf_count, e.splat_count, e.encoded_count,
                                          counts[b].direct);
        e.top_node = t;
        e.level = cut.level[t];
        offset += pool::brick_padded_size(e.size);
    }
    out.data.assign(offset, std::byte{0});
}

/// Adds one splat's codec error (decoded `d` against the float splat `sp` of colour `col`).
void measure(CodecError& err, const pool::Splat& sp, const pool::DecodedSplat& d, pool::Rgba8 col,
             double quantum, double step) {
    const double r = sp.radius;
    const double dp[3] = {double(d.position.x) - sp.position.x, double(d.position.y) - sp.position.y,
                          double(d.position.z) - sp.position.z};
    const double pe = std::sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]) / r;
    err.position_max = std::max(err.position_max, pe);
    err.position_sum += pe;
    for (double x : dp) err.position_quanta_max = std::max(err.position_quanta_max, std::fabs(x) / quantum);
    const double nl = std::sqrt(double(sp.normal.x) * sp.normal.x + double(sp.normal.y) * sp.normal.y +
                                double(sp.normal.z) * sp.normal.z);
    const double dot = (double(d.normal.x) * sp.normal.x + double(d.normal.y) * sp.normal.y +
                        double(d.normal.z) * sp.normal.z) /
                       nl;
    const double angle = std::acos(std::clamp(dot, -1.0, 1.0)) * 180.0 / k_pi;
    err.normal_max_deg = std::max(err.normal_max_deg, angle);
    err.normal_sum_deg += angle;
    const double growth = double(d.radius) / r - 1.0;
    if (growth >= 0) {
        err.radius_growth_max = std::max(err.radius_growth_max, growth);
        err.radius_growth_sum += growth;
    } else {
        err.radius_shrink_max = std::max(err.radius_shrink_max, -growth);
    }
    if (double(d.radius) > r * step) ++err.radii_raised;
    err.color_max = std::max({err.color_max, std::uint32_t(std::abs(int(d.color.r) - int(col.r))),
                              std::uint32_t(std::abs(int(d.color.g) - int(col.g))),
                              std::uint32_t(std::abs(int(d.color.b) - int(col.b)))});
    ++err.splats;
}

/// The brick header for the distinct splats `brick_splats` of entry `e`: the quantization cube is the
/// brick cube grown to hold every centre (replicas reach outside), the radius exponent from the largest.
pool::BrickHeader brick_header(std::size_t b, const pool::BrickEntry& e,
                               const std::vector<const pool::Splat*>& brick_splats) {
    double lo[3], hi[3];
    for (int ax = 0; ax < 3; ++ax) lo[ax] = e.cube_min[ax], hi[ax] = double(e.cube_min[ax]) + e.cube_size;
    float max_radius = 0;
    for (const pool::Splat* sp : brick_splats) {
        const float p[3] = {sp->position.x, sp->position.y, sp->position.z};
        for (int ax = 0; ax < 3; ++ax)
            lo[ax] = std::min(lo[ax], double(p[ax])), hi[ax] = std::max(hi[ax], double(p[ax]));
        max_radius = std::max(max_radius, sp->radius);
    }
    pool::BrickHeader h{};
    double qsize = 0;
    for (int ax = 0; ax < 3; ++ax) {
        h.quant_min[ax] = round_down(lo[ax]);
        qsize = std::max(qsize, hi[ax] - double(h.quant_min[ax]));
    }
    h.quant_size = round_up(qsize);
    if (!std::isfinite(h.quant_size) || !std::isfinite(h.quant_min[0]) || !std::isfinite(h.quant_min[1]) ||
        !std::isfinite(h.quant_min[2]) || !std::isfinite(max_radius))
        throw Error("brick " + std::to_string(b) + ": a splat position or radius is not finite");
    h.node_count = e.node_count;
    h.leaf_count = e.leaf_count;
    h.splat_count = e.splat_count;
    h.encoded_count = e.encoded_count;
    h.radius_log2_min = pool::radius_log2_min_for(max_radius, h.quant_size);
    return h;
}

/// Point id -> the index of its first encoded splat within one brick: open addressing with linear
/// probing over a power-of-two table at most half full, sized per brick (reset(references)). It
/// replaced a std::unordered_map whose node allocations and frees took about 15 % of the brick
/// step (perf, prt-bricks on a culled 1M room, one thread).
class PointIndex {
public:
    /// Empties the index for up to `count` points.
    void reset(std::size_t count) {
        std::size_t size = 64;
        while (size < 2 * count) size *= 2;
        m_shift = 64 - static_cast<unsigned>(std::countr_zero(size));
        m_keys.assign(size, k_empty);
        m_values.resize(size);
    }
    /// The index stored for `point`, or `value` stored for it now (second: true) if it had none.
    std::pair<std::uint32_t, bool> try_emplace(std::uint32_t point, std::uint32_t value) {
        const std::size_t mask = m_keys.size() - 1;
        const std::uint64_t key = point;
        for (std::size_t i = (key * 0x9E3779B97F4A7C15ull) >> m_shift;; i = (i + 1) & mask) {
            if (m_keys[i] == key) return {m_values[i], false};
            if (m_keys[i] == k_empty) {
                m_keys[i] = key;
                m_values[i] = value;
                return {value, true};
            }
        }
    }

private:
    static constexpr std::uint64_t k_empty = ~std::uint64_t{0};  // no point id is 2^64 - 1
    std::vector<std::uint64_t> m_keys;
    std::vector<std::uint32_t> m_values;
    unsigned m_shift = 58;
};

/// Phase 3b: writes bricks' payloads, checksums and LOD discs (one worker's scratch).
class BrickEncoder {
public:
    /// One worker's reusable buffers.
    struct Scratch {
        std::vector<std::uint32_t> src, nodes, leaf_info;
        std::vector<NodeCell> cells;                                  // per src entry
        std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves;  // (source leaf, local node)
        std::vector<std::uint8_t> centre;  // per reference: its centre lies in its leaf's half-open cell
        std::vector<const pool::Splat*> splats;   // per reference, in leaf order
        std::vector<std::uint32_t> refs;          // per reference: index into `encoded`
        std::vector<const pool::Splat*> encoded;  // the distinct splats, in order of first reference
        PointIndex first;                         // point -> its first encoded index
        std::vector<std::uint32_t> parent;        // per local node (root: itself)
        std::vector<std::uint32_t> level_nodes;   // non-empty nodes per local level
        std::vector<LodSum> lod_sum, lod_any;     // per LOD prefix node
        std::vector<pool::LodSplat> lod_disc;
        std::vector<double> lod_cover;
    };

    BrickEncoder(const pool::SplatOctreeSections& octree, std::span<const pool::Rgba8> colors,
                 const TopCut& cut, BrickParams::Direct direct, BrickedOctree& out)
        : m_octree(octree), m_colors(colors), m_cut(cut), m_direct(direct), m_out(out) {}

    /// The compressed splats of brick b (the one whose top node is `top_node`), whether it is direct,
    /// and its LOD prefix's nodes (`lod_splats` M, 0: none).
    BrickCounts count(std::uint32_t top_node, std::uint32_t lod_splats, Scratch& scratch) const {
        const std::size_t references = gather(top_node, scratch, false);
        const bool direct = store_direct(m_direct, references, scratch.encoded.size());
        return BrickCounts{std::uint32_t(direct ? references : scratch.encoded.size()),
                           lod_splats > 0 ? lod_prefix_nodes(lod_splats, references, scratch) : 0u, direct};
    }

    /// Brick b: its subtree renumbered breadth first from 0, its leaves in the source's leaf order,
    /// its distinct splats encoded and measured, its references; returns its LOD sums (its disc is
    /// written to out.lod). The sums count each point once, area-weighted, in the leaf whose
    /// half-open cell holds its centre (every point has exactly one such leaf in the octree, and
    /// culling keeps it there), so the sums of all bricks count every point once and a brick's sums
    /// do not depend on other bricks (an out-of-core build makes them cell by cell).
    LodSum encode(std::size_t b, CodecError& err, Scratch& scratch) const {
        pool::BrickEntry& e = m_out.table[b];
        gather(e.top_node, scratch, true);
        const bool direct = store_direct(m_direct, scratch.splats.size(), scratch.encoded.size());
        if (direct) scratch.encoded = scratch.splats;  // in leaf order, a replica once per leaf
        if (scratch.encoded.size() != e.encoded_count || scratch.splats.size() != e.splat_count)
            throw Error("brick " + std::to_string(b) + ": counts changed between passes (internal error)");
        std::byte* base = m_out.data.data() + e.offset;
        pool::BrickHeader h = brick_header(b, e, scratch.encoded);
        h.layout = direct ? pool::k_brick_direct : pool::k_brick_referenced;
        std::memcpy(base, &h, sizeof h);
        std::memcpy(base + pool::brick_nodes_offset(), scratch.nodes.data(), 4 * scratch.nodes.size());
        std::memcpy(base + pool::brick_leaf_info_offset(h.node_count), scratch.leaf_info.data(),
                    4 * scratch.leaf_info.size());
        std::byte* refs = base + pool::brick_refs_offset(h.node_count, h.leaf_count);
        if (direct) {
            // no references: splat i of the leaves is encoded splat i
        } else if (pool::brick_ref_bytes(h.encoded_count) == 2) {
            for (std::size_t k = 0; k < scratch.refs.size(); ++k) {
                const auto r = static_cast<std::uint16_t>(scratch.refs[k]);
                std::memcpy(refs + 2 * k, &r, 2);
            }
        } else {
            std::memcpy(refs, scratch.refs.data(), 4 * scratch.refs.size());
        }
        auto* out_splats = reinterpret_cast<pool::CompressedSplat*>(
            base +
            pool::brick_splats_offset(h.node_count, h.leaf_count, h.splat_count, h.encoded_count, direct));
        const double quantum = double(h.quant_size) / pool::k_position_max_code;
        const double step = std::exp2(1.0 / pool::k_radius_steps_per_octave) * (1.0 + 1e-6);
        for (std::size_t k = 0; k < scratch.encoded.size(); ++k) {
            const pool::Splat& sp = *scratch.encoded[k];
            const pool::Rgba8 col = color(sp);
            if (!pool::encode_splat(sp.position, sp.radius, sp.normal, col, h, &out_splats[k]))
                throw Error("brick " + std::to_string(b) + ": radius " + std::to_string(sp.radius) +
                            " not representable (internal error)");
            measure(err, sp, pool::decode_splat(out_splats[k], h), col, quantum, step);
        }
        LodSum sum, any;  // any: every reference, for the disc of a brick holding only replicas
        for (std::size_t k = 0; k < scratch.splats.size(); ++k) {
            const pool::Splat& sp = *scratch.splats[k];
            const pool::Rgba8 col = color(sp);
            const double r = sp.radius;
            const double w = std::max(k_pi * r * r, 1e-300);
            const double p[3] = {sp.position.x, sp.position.y, sp.position.z};
            const double nn[3] = {sp.normal.x, sp.normal.y, sp.normal.z};
            const double c[3] = {double(col.r), double(col.g), double(col.b)};
            any.add_point(w, p, nn, c);
            if (scratch.centre[k]) sum.add_point(w, p, nn, c);
        }
        e.checksum = pool::checksum({base, static_cast<std::size_t>(e.size)});
        if (!m_out.lod_table.empty()) encode_lod_prefix(b, h, scratch);
        // the brick's LOD disc: its sphere holds every splat's disc
        pool::LodSplat disc = lod_from_sum(sum.w > 0 ? sum : any);
        double cover = 0;
        for (const pool::Splat* sp : scratch.encoded)
            cover = std::max(cover, distance(sp->position, disc.position) + sp->radius);
        disc.radius = round_up(cover);
        m_out.lod[e.top_node] = disc;
        return sum;
    }

private:
    /// The nodes of the brick's LOD prefix: levels 0..D (breadth first, so a prefix of the node
    /// array), D the deepest level whose non-empty nodes hold at least `m` references on average
    /// (level 0 always).
    static std::uint32_t lod_prefix_nodes(std::uint32_t m, std::size_t references, Scratch& s) {
        s.level_nodes.assign(1, 0);
        const std::uint32_t root_level = s.cells[0].level;
        for (std::size_t i = 0; i < s.nodes.size(); ++i) {
            const std::uint32_t l = s.cells[i].level - root_level;
            if (l >= s.level_nodes.size()) s.level_nodes.resize(l + 1, 0);
            if (pool::node_type(s.nodes[i]) != NodeType::empty_leaf) ++s.level_nodes[l];
        }
        std::uint32_t deepest = 0;
        while (deepest + 1 < s.level_nodes.size() &&
               std::uint64_t(s.level_nodes[deepest + 1]) * m <= references)
            ++deepest;
        std::uint32_t k = 0;
        while (k < s.nodes.size() && s.cells[k].level - root_level <= deepest) ++k;
        return k;
    }

    /// The discs of brick b's LOD prefix (count() gave its size) into out.lod_nodes, its entry into
    /// out.lod_table: each reference's sums go to its leaf's deepest prefix ancestor, then up the
    /// prefix; each disc's radius covers every splat disc below its node.
    void encode_lod_prefix(std::size_t b, const pool::BrickHeader& h, Scratch& s) const {
        pool::BrickLod& lt = m_out.lod_table[b];
        const std::uint32_t k = lt.node_count;
        s.lod_sum.assign(k, LodSum{});
        s.lod_any.assign(k, LodSum{});
        const auto prefix_ancestor = [&](std::uint32_t n) {
            while (n >= k) n = s.parent[n];
            return n;
        };
        for (std::size_t l = 0; l < s.leaves.size(); ++l) {
            const std::uint32_t n = prefix_ancestor(s.leaves[l].second);
            for (std::uint32_t r = s.leaf_info[l]; r < s.leaf_info[l + 1]; ++r) {
                const pool::Splat& sp = *s.splats[r];
                const pool::Rgba8 col = color(sp);
                const double w = std::max(k_pi * double(sp.radius) * sp.radius, 1e-300);
                const double p[3] = {sp.position.x, sp.position.y, sp.position.z};
                const double nn[3] = {sp.normal.x, sp.normal.y, sp.normal.z};
                const double c[3] = {double(col.r), double(col.g), double(col.b)};
                s.lod_any[n].add_point(w, p, nn, c);
                if (s.centre[r]) s.lod_sum[n].add_point(w, p, nn, c);
            }
        }
        for (std::uint32_t i = k; i-- > 1;) {  // children after their parent
            s.lod_sum[s.parent[i]].add(s.lod_sum[i]);
            s.lod_any[s.parent[i]].add(s.lod_any[i]);
        }
        s.lod_disc.assign(k, pool::LodSplat{});
        s.lod_cover.assign(k, -1.0);
        for (std::uint32_t i = 0; i < k; ++i)
            if (s.lod_any[i].w > 0)
                s.lod_disc[i] = lod_from_sum(s.lod_sum[i].w > 0 ? s.lod_sum[i] : s.lod_any[i]);
        for (std::size_t l = 0; l < s.leaves.size(); ++l) {
            const std::uint32_t n0 = prefix_ancestor(s.leaves[l].second);
            for (std::uint32_t r = s.leaf_info[l]; r < s.leaf_info[l + 1]; ++r) {
                const pool::Splat& sp = *s.splats[r];
                for (std::uint32_t n = n0;; n = s.parent[n]) {
                    s.lod_cover[n] =
                        std::max(s.lod_cover[n], distance(sp.position, s.lod_disc[n].position) + sp.radius);
                    if (n == 0) break;
                }
            }
        }
        float max_radius = 0;
        for (std::uint32_t i = 0; i < k; ++i) {
            s.lod_disc[i].radius = s.lod_cover[i] > 0 ? round_up(s.lod_cover[i]) : 0.0f;
            max_radius = std::max(max_radius, s.lod_disc[i].radius);
        }
        for (int ax = 0; ax < 3; ++ax) lt.quant_min[ax] = h.quant_min[ax];
        lt.quant_size = h.quant_size;
        lt.radius_log2_min = pool::radius_log2_min_for(max_radius, h.quant_size);
        pool::BrickHeader dh = h;  // the discs' decode cube: the brick's, with their own exponent
        dh.radius_log2_min = lt.radius_log2_min;
        for (std::uint32_t i = 0; i < k; ++i) {
            m_out.lod_nodes[lt.first + i] = s.nodes[i];
            pool::CompressedSplat& disc = m_out.lod_discs[lt.first + i];
            disc = pool::CompressedSplat{};
            const pool::LodSplat& d = s.lod_disc[i];
            if (d.radius > 0 && !pool::encode_splat(d.position, d.radius, d.normal, d.color, dh, &disc))
                throw Error("brick " + std::to_string(b) + ": LOD disc radius " + std::to_string(d.radius) +
                            " not representable (internal error)");
        }
    }

    pool::Rgba8 color(const pool::Splat& sp) const {
        return sp.point < m_colors.size() ? m_colors[sp.point] : pool::Rgba8{255, 255, 255, 255};
    }

    /// Two references hold the same splat: the same point with the same float disc (replicas are
    /// copies; a disc that differs is encoded again).
    static bool same_splat(const pool::Splat& a, const pool::Splat& b) {
        return a.point == b.point && std::memcmp(&a, &b, sizeof(pool::Splat)) == 0;
    }

    /// The brick's nodes (breadth first from 0), leaf ranges, references and distinct splats into `s`;
    /// returns the number of references. Without `full` (count()), only the nodes, cells, leaves
    /// and distinct splats: not the references' pointers, centre flags and indices, which only
    /// encode() reads.
    std::size_t gather(std::uint32_t top_node, Scratch& s, bool full) const {
        s.src.assign(1, m_cut.src[top_node]);
        s.parent.assign(1, 0);
        s.cells.assign(1, NodeCell{m_cut.level[top_node],
                                   {m_cut.cell[3 * top_node], m_cut.cell[3 * top_node + 1],
                                    m_cut.cell[3 * top_node + 2]}});
        s.nodes.clear();
        s.leaves.clear();
        for (std::size_t i = 0; i < s.src.size(); ++i) {
            const std::uint32_t w = m_octree.nodes[s.src[i]];
            const std::uint32_t a = pool::node_address(w);
            switch (pool::node_type(w)) {
                case NodeType::internal:
                    s.nodes.push_back(pool::make_node(NodeType::internal, std::uint32_t(s.src.size())));
                    for (std::uint32_t c = 0; c < 8; ++c) {
                        s.src.push_back(a + c);
                        s.parent.push_back(std::uint32_t(i));
                        const NodeCell& pc = s.cells[i];
                        s.cells.push_back(NodeCell{pc.level + 1,
                                                   {2 * pc.cell[0] + (c & 1u), 2 * pc.cell[1] + (c >> 1 & 1u),
                                                    2 * pc.cell[2] + (c >> 2 & 1u)}});
                    }
                    break;
                case NodeType::filled_leaf:
                    s.leaves.emplace_back(a, std::uint32_t(i));
                    s.nodes.push_back(0);  // set below
                    break;
                default:
                    s.nodes.push_back(pool::make_node(NodeType::empty_leaf, 0));
                    break;
            }
        }
        std::sort(s.leaves.begin(), s.leaves.end());
        s.leaf_info.assign(s.leaves.size() + 1, 0);
        s.splats.clear();
        s.centre.clear();
        s.refs.clear();
        s.encoded.clear();
        std::size_t references = 0;
        for (const auto& leaf : s.leaves)
            references += m_octree.leaf_info[leaf.first + 1] - m_octree.leaf_info[leaf.first];
        s.first.reset(references);
        for (std::size_t l = 0; l < s.leaves.size(); ++l) {
            s.nodes[s.leaves[l].second] = pool::make_node(NodeType::filled_leaf, std::uint32_t(l));
            const std::uint32_t sb = m_octree.leaf_info[s.leaves[l].first],
                                se = m_octree.leaf_info[s.leaves[l].first + 1];
            double lo[3], hi[3];
            if (full) {
                const NodeCell& lc = s.cells[s.leaves[l].second];
                node_box(m_octree.info, lc.level, lc.cell, lo, hi);
            }
            for (std::uint32_t k = sb; k < se; ++k) {
                const pool::Splat& sp = m_octree.splats[k];
                const auto [at, fresh] = s.first.try_emplace(sp.point, std::uint32_t(s.encoded.size()));
                const bool distinct = fresh || !same_splat(*s.encoded[at], sp);
                if (full) {
                    // encode() reads each splat's colour by its point index, scattered over the whole
                    // colour array: fetched here, the misses overlap this loop's work.
                    if (sp.point < m_colors.size()) __builtin_prefetch(m_colors.data() + sp.point);
                    s.splats.push_back(&sp);
                    const double cp[3] = {sp.position.x, sp.position.y, sp.position.z};
                    bool inside = true;
                    for (int ax = 0; ax < 3; ++ax) inside = inside && cp[ax] >= lo[ax] && cp[ax] < hi[ax];
                    s.centre.push_back(inside);
                    s.refs.push_back(distinct ? std::uint32_t(s.encoded.size()) : at);
                }
                if (distinct) s.encoded.push_back(&sp);
            }
            s.leaf_info[l + 1] = std::uint32_t(s.splats.size());
        }
        return references;
    }

    const pool::SplatOctreeSections& m_octree;
    std::span<const pool::Rgba8> m_colors;
    const TopCut& m_cut;
    BrickParams::Direct m_direct;
    BrickedOctree& m_out;
};

/// Phase 4: LOD discs of the internal top nodes, children first (they come after their parent).
/// A node whose bricks hold only replicas (no centre, zero weight) gets the disc of its children's
/// discs, each weighted by its area.
void internal_lods(BrickedOctree& out, std::vector<LodSum>& sums) {
    for (std::size_t t = out.top_nodes.size(); t-- > 0;) {
        const std::uint32_t w = out.top_nodes[t];
        if (pool::node_type(w) != NodeType::internal) continue;
        const std::uint32_t a = pool::node_address(w);
        LodSum sum, discs;
        for (std::uint32_t c = 0; c < 8; ++c) {
            sum.add(sums[a + c]);
            const pool::LodSplat& d = out.lod[a + c];
            if (!(d.radius > 0)) continue;
            const double p[3] = {d.position.x, d.position.y, d.position.z};
            const double n[3] = {d.normal.x, d.normal.y, d.normal.z};
            const double col[3] = {double(d.color.r), double(d.color.g), double(d.color.b)};
            discs.add_point(k_pi * double(d.radius) * d.radius, p, n, col);
        }
        pool::LodSplat disc = lod_from_sum(sum.w > 0 ? sum : discs);
        double cover = 0;
        for (std::uint32_t c = 0; c < 8; ++c)
            if (out.lod[a + c].radius > 0)
                cover =
                    std::max(cover, distance(out.lod[a + c].position, disc.position) + out.lod[a + c].radius);
        disc.radius = round_up(cover);
        out.lod[t] = disc;
        sums[t] = sum;
    }
}

/// BrickInfo from the octree's and the table's facts, and the build's statistics.
BrickStats fill_info(BrickedOctree& out, const pool::OctreeInfo& oi, std::uint32_t top_depth,
                     std::uint32_t limit, bool colors) {
    pool::BrickInfo& info = out.info;
    for (int ax = 0; ax < 3; ++ax) info.root_min[ax] = oi.root_min[ax];
    info.root_size = oi.root_size;
    info.depth = oi.depth;
    info.brick_count = std::uint32_t(out.table.size());
    info.top_node_count = std::uint32_t(out.top_nodes.size());
    info.brick_splat_limit = limit;
    info.flags = pool::k_bricks_indexed | (colors ? pool::k_bricks_colors : 0u) |
                 (!out.lod_table.empty() ? pool::k_bricks_lod : 0u) |
                 ((oi.flags & pool::k_octree_culled) ? pool::k_bricks_culled : 0u) |
                 ((oi.flags & pool::k_octree_replicated) ? pool::k_bricks_replicated : 0u);
    info.unique_splats = oi.unique_splats;
    BrickStats stats;
    stats.bricks = info.brick_count;
    stats.top_nodes = info.top_node_count;
    stats.top_depth = top_depth;
    stats.min_brick_splats = out.table.empty() ? 0 : 0xFFFFFFFFu;
    for (const pool::BrickEntry& e : out.table) {
        if (pool::brick_entry_is_direct(e)) ++stats.direct_bricks;
        info.splat_count += e.splat_count;
        info.encoded_splats += e.encoded_count;
        info.max_brick_splats = std::max(info.max_brick_splats, e.splat_count);
        stats.min_brick_splats = std::min(stats.min_brick_splats, e.splat_count);
    }
    stats.max_brick_splats = info.max_brick_splats;
    stats.splats = info.splat_count;
    stats.encoded = info.encoded_splats;
    stats.lod_nodes = out.lod_nodes.size();
    stats.data_bytes = out.data.size();
    return stats;
}

}  // namespace

BrickPart build_brick_part(const pool::SplatOctreeSections& octree, std::span<const pool::Rgba8> colors,
                           const BrickParams& params, NodeCell root) {
    if (octree.nodes.empty()) throw Error("the octree has no nodes");
    const std::uint32_t limit = std::max<std::uint32_t>(params.brick_splats, 1);
    BrickPart part;
    BrickedOctree& out = part.bricks;
    const Subtrees sub = subtree_sizes(octree.nodes, octree.leaf_info);              // 1
    const TopCut cut = cut_top_tree(octree.nodes, sub, limit, root, out.top_nodes);  // 2
    part.top_depth = *std::max_element(cut.level.begin(), cut.level.end());
    const std::size_t bricks = cut.brick_top.size();
    const unsigned threads = resolve_threads(params.threads);
    const BrickEncoder encoder(octree, colors, cut, params.direct, out);
    std::vector<BrickCounts> counts(bricks);
    parallel_chunks(bricks, 1, threads, [&](std::size_t begin, std::size_t end, unsigned) {  // 3a
        BrickEncoder::Scratch scratch;
        for (std::size_t b = begin; b < end; ++b)
            counts[b] = encoder.count(cut.brick_top[b], params.lod_splats, scratch);
    });
    lay_out_bricks(cut, sub, octree.info, counts, params.lod_splats > 0, out);
    part.sums.assign(out.top_nodes.size(), LodSum{});
    out.lod.assign(out.top_nodes.size(), pool::LodSplat{});
    std::vector<CodecError> errors(threads);
    std::atomic<std::uint64_t> done{0};
    parallel_chunks(bricks, 1, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {  // 3b
        BrickEncoder::Scratch scratch;
        for (std::size_t b = begin; b < end; ++b) {
            part.sums[out.table[b].top_node] = encoder.encode(b, errors[worker], scratch);
            const std::uint64_t now = done.fetch_add(1) + 1;
            if (worker == 0 && params.progress) params.progress(now, bricks);
        }
    });
    if (params.progress) params.progress(bricks, bricks);
    for (const CodecError& e : errors) part.error.merge(e);
    return part;
}

BrickStats finish_bricks(BrickedOctree& out, std::vector<LodSum>& sums, const pool::OctreeInfo& octree_info,
                         std::uint32_t top_depth, const BrickParams& params, bool colors) {
    internal_lods(out, sums);  // 4
    return fill_info(out, octree_info, top_depth, std::max<std::uint32_t>(params.brick_splats, 1), colors);
}

BrickedOctree build_bricks(const pool::SplatOctreeSections& octree, std::span<const pool::Rgba8> colors,
                           const BrickParams& params, BrickStats* stats_out) {
    const double start = tool::now_seconds();
    BrickPart part = build_brick_part(octree, colors, params, NodeCell{});
    BrickStats stats =
        finish_bricks(part.bricks, part.sums, octree.info, part.top_depth, params, !colors.empty());
    stats.data_bytes = part.bricks.data.size();
    stats.error = part.error;
    stats.seconds = tool::now_seconds() - start;
    if (stats_out) *stats_out = stats;
    return std::move(part.bricks);
}

void add_brick_sections(BrickedOctree bricks, pool::PoolWriter& writer) {
    writer.add_array(pool::SectionType::brick_data, std::move(bricks.data));
    add_brick_index_sections(std::move(bricks), writer);
}

void add_brick_index_sections(BrickedOctree bricks, pool::PoolWriter& writer) {
    writer.add_array(pool::SectionType::brick_info, std::vector<pool::BrickInfo>{bricks.info});
    writer.add_array(pool::SectionType::brick_top_nodes, std::move(bricks.top_nodes));
    writer.add_array(pool::SectionType::brick_table, std::move(bricks.table));
    writer.add_array(pool::SectionType::lod_splats, std::move(bricks.lod));
    if (!bricks.lod_table.empty()) {
        writer.add_array(pool::SectionType::brick_lod, std::move(bricks.lod_table));
        writer.add_array(pool::SectionType::lod_nodes, std::move(bricks.lod_nodes));
        writer.add_array(pool::SectionType::lod_discs, std::move(bricks.lod_discs));
    } else {
        for (const pool::SectionType t :
             {pool::SectionType::brick_lod, pool::SectionType::lod_nodes, pool::SectionType::lod_discs})
            writer.remove(t);
    }
}

}  // namespace prt::pre
