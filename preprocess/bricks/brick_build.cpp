// PointRT preprocess: the brick builder (brick_build.h; format in formats/POOL.md, "Bricks and level
// of detail").
//
// 1. Subtree sizes bottom-up over the octree's node array (children are stored after their parent).
// 2. The top tree, breadth first from the root: an empty leaf stays empty; a node holding at most N
//    splats (or a filled leaf, whatever it holds) becomes a brick; any other node stays internal.
// 3. Payload offsets from the subtree counts (each brick 64-byte aligned), then every brick in
//    parallel: its subtree renumbered breadth first from 0, its filled leaves in the source's leaf
//    order, its splats encoded (and the codec's error measured against the float splats), its
//    checksum and its LOD disc.
// 4. LOD discs of the top tree's internal nodes, bottom-up from their children's discs.
#include "brick_build.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <string>

#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool.h"

namespace prt::pre {

using pool::NodeType;

namespace {

constexpr double k_pi = 3.14159265358979323846;

/// Area-weighted sums of a node's splats (LOD), each replica weighted 1 / its copies.
struct LodSum {
    double w = 0, p[3] = {0, 0, 0}, n[3] = {0, 0, 0}, c[3] = {0, 0, 0};
    void add(const LodSum& o) {
        w += o.w;
        for (int a = 0; a < 3; ++a) p[a] += o.p[a], n[a] += o.n[a], c[a] += o.c[a];
    }
};

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

BrickedOctree build_bricks(const pool::SplatOctreeSections& octree, std::span<const pool::Rgba8> colors,
                           const BrickParams& params, BrickStats* stats_out) {
    const double start = tool::now_seconds();
    const std::span<const std::uint32_t> nodes = octree.nodes;
    const std::span<const std::uint32_t> leaf_info = octree.leaf_info;
    const std::span<const pool::Splat> splats = octree.splats;
    const std::size_t n = nodes.size();
    if (n == 0) throw Error("the octree has no nodes");
    const std::uint32_t limit = std::max<std::uint32_t>(params.brick_splats, 1);

    // 1. subtree sizes: stored splats, nodes, filled leaves
    std::vector<std::uint64_t> sub_splats(n, 0);
    std::vector<std::uint32_t> sub_nodes(n, 1), sub_leaves(n, 0);
    for (std::size_t i = n; i-- > 0;) {
        const std::uint32_t a = pool::node_address(nodes[i]);
        switch (pool::node_type(nodes[i])) {
            case NodeType::internal:
                for (std::uint32_t c = 0; c < 8; ++c) {
                    sub_splats[i] += sub_splats[a + c];
                    sub_nodes[i] += sub_nodes[a + c];
                    sub_leaves[i] += sub_leaves[a + c];
                }
                break;
            case NodeType::filled_leaf:
                sub_splats[i] = leaf_info[a + 1] - leaf_info[a];
                sub_leaves[i] = 1;
                break;
            default:
                break;
        }
    }

    // 2. the top tree, breadth first: top node t stands for source node src[t]
    BrickedOctree out;
    std::vector<std::uint32_t> src{0}, level{0}, cell{0, 0, 0};
    std::vector<std::uint32_t> brick_top;  // top node of each brick
    for (std::size_t t = 0; t < src.size(); ++t) {
        const std::uint32_t s = src[t];
        const NodeType type = pool::node_type(nodes[s]);
        if (type == NodeType::empty_leaf) {
            out.top_nodes.push_back(pool::make_node(NodeType::empty_leaf, 0));
        } else if (type == NodeType::filled_leaf || sub_splats[s] <= limit) {
            if (sub_splats[s] > 0xFFFFFFFFull)
                throw Error("a leaf holds " + std::to_string(sub_splats[s]) +
                            " splats; a brick holds at most 2^32 - 1");
            out.top_nodes.push_back(pool::make_node(NodeType::brick, std::uint32_t(brick_top.size())));
            brick_top.push_back(std::uint32_t(t));
        } else {
            const std::uint32_t first = std::uint32_t(src.size());
            if (std::uint64_t(first) + 8 > pool::k_node_address_max)
                throw Error("the top tree exceeds 2^30 nodes");
            out.top_nodes.push_back(pool::make_node(NodeType::internal, first));
            const std::uint32_t a = pool::node_address(nodes[s]);
            for (std::uint32_t c = 0; c < 8; ++c) {
                src.push_back(a + c);
                level.push_back(level[t] + 1);
                for (int ax = 0; ax < 3; ++ax) cell.push_back(2 * cell[3 * t + ax] + ((c >> ax) & 1));
            }
        }
    }
    const std::size_t top_count = out.top_nodes.size();
    const std::size_t bricks = brick_top.size();

    // 3. payload offsets, then the bricks in parallel
    const pool::OctreeInfo& oi = octree.info;
    out.table.resize(bricks);
    std::uint64_t offset = 0;
    for (std::size_t b = 0; b < bricks; ++b) {
        const std::uint32_t t = brick_top[b];
        const std::uint32_t s = src[t];
        pool::BrickEntry& e = out.table[b];
        const double size = double(oi.root_size) / double(std::uint64_t(1) << level[t]);
        for (int ax = 0; ax < 3; ++ax)
            e.cube_min[ax] = float(double(oi.root_min[ax]) + size * cell[3 * t + ax]);
        e.cube_size = float(size);
        e.offset = offset;
        e.node_count = sub_nodes[s];
        e.leaf_count = sub_leaves[s];
        e.splat_count = std::uint32_t(sub_splats[s]);
        e.size = pool::brick_payload_size(e.node_count, e.leaf_count, e.splat_count);
        e.top_node = t;
        e.level = level[t];
        offset += (e.size + pool::k_brick_alignment - 1) / pool::k_brick_alignment * pool::k_brick_alignment;
    }
    out.data.assign(offset, std::byte{0});

    // copies of each point among the stored splats: a replica weighs 1 / copies in the LOD sums
    std::uint32_t max_point = 0;
    for (const pool::Splat& sp : splats) max_point = std::max(max_point, sp.point);
    std::vector<std::uint32_t> copies(splats.empty() ? 0 : std::size_t(max_point) + 1, 0);
    for (const pool::Splat& sp : splats) ++copies[sp.point];
    const auto color_of = [&](const pool::Splat& sp) {
        return sp.point < colors.size() ? colors[sp.point] : pool::Rgba8{255, 255, 255, 255};
    };

    std::vector<LodSum> sums(top_count);
    out.lod.assign(top_count, pool::LodSplat{});
    const unsigned threads = resolve_threads(params.threads);
    std::vector<CodecError> errors(threads);
    std::atomic<std::uint64_t> done{0};
    parallel_chunks(bricks, 1, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {
        std::vector<std::uint32_t> local_src, local_nodes;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves;  // (source leaf, local node)
        std::vector<const pool::Splat*> brick_splats;
        for (std::size_t b = begin; b < end; ++b) {
            pool::BrickEntry& e = out.table[b];
            // the subtree, breadth first from 0
            local_src.assign(1, src[e.top_node]);
            local_nodes.clear();
            leaves.clear();
            for (std::size_t i = 0; i < local_src.size(); ++i) {
                const std::uint32_t w = nodes[local_src[i]];
                const std::uint32_t a = pool::node_address(w);
                switch (pool::node_type(w)) {
                    case NodeType::internal:
                        local_nodes.push_back(
                            pool::make_node(NodeType::internal, std::uint32_t(local_src.size())));
                        for (std::uint32_t c = 0; c < 8; ++c) local_src.push_back(a + c);
                        break;
                    case NodeType::filled_leaf:
                        leaves.emplace_back(a, std::uint32_t(i));
                        local_nodes.push_back(0);  // set below
                        break;
                    default:
                        local_nodes.push_back(pool::make_node(NodeType::empty_leaf, 0));
                        break;
                }
            }
            std::sort(leaves.begin(), leaves.end());
            std::byte* base = out.data.data() + e.offset;
            std::vector<std::uint32_t> local_leaf_info(leaves.size() + 1, 0);
            brick_splats.clear();
            for (std::size_t l = 0; l < leaves.size(); ++l) {
                local_nodes[leaves[l].second] = pool::make_node(NodeType::filled_leaf, std::uint32_t(l));
                const std::uint32_t sb = leaf_info[leaves[l].first], se = leaf_info[leaves[l].first + 1];
                for (std::uint32_t k = sb; k < se; ++k) brick_splats.push_back(&splats[k]);
                local_leaf_info[l + 1] = std::uint32_t(brick_splats.size());
            }
            // quantization cube: the brick cube grown to hold every centre (replicas reach outside)
            double lo[3], hi[3];
            for (int ax = 0; ax < 3; ++ax)
                lo[ax] = e.cube_min[ax], hi[ax] = double(e.cube_min[ax]) + e.cube_size;
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
            if (!std::isfinite(h.quant_size) || !std::isfinite(h.quant_min[0]) ||
                !std::isfinite(h.quant_min[1]) || !std::isfinite(h.quant_min[2]) ||
                !std::isfinite(max_radius))
                throw Error("brick " + std::to_string(b) + ": a splat position or radius is not finite");
            h.node_count = e.node_count;
            h.leaf_count = e.leaf_count;
            h.splat_count = e.splat_count;
            h.radius_log2_min = pool::radius_log2_min_for(max_radius, h.quant_size);
            std::memcpy(base, &h, sizeof h);
            std::memcpy(base + pool::brick_nodes_offset(), local_nodes.data(), 4 * local_nodes.size());
            std::memcpy(base + pool::brick_leaf_info_offset(h.node_count), local_leaf_info.data(),
                        4 * local_leaf_info.size());
            auto* out_splats = reinterpret_cast<pool::CompressedSplat*>(
                base + pool::brick_splats_offset(h.node_count, h.leaf_count));
            // encode and measure; LOD sums
            CodecError& err = errors[worker];
            const double quantum = double(h.quant_size) / pool::k_position_max_code;
            const double step = std::exp2(1.0 / pool::k_radius_steps_per_octave) * (1.0 + 1e-6);
            LodSum sum;
            for (std::size_t k = 0; k < brick_splats.size(); ++k) {
                const pool::Splat& sp = *brick_splats[k];
                const pool::Rgba8 col = color_of(sp);
                if (!pool::encode_splat(sp.position, sp.radius, sp.normal, col, h, &out_splats[k]))
                    throw Error("brick " + std::to_string(b) + ": radius " + std::to_string(sp.radius) +
                                " not representable (internal error)");
                const pool::DecodedSplat d = pool::decode_splat(out_splats[k], h);
                const double r = sp.radius;
                const double dp[3] = {double(d.position.x) - sp.position.x,
                                      double(d.position.y) - sp.position.y,
                                      double(d.position.z) - sp.position.z};
                const double pe = std::sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]) / r;
                err.position_max = std::max(err.position_max, pe);
                err.position_sum += pe;
                for (double x : dp)
                    err.position_quanta_max = std::max(err.position_quanta_max, std::fabs(x) / quantum);
                const double nl =
                    std::sqrt(double(sp.normal.x) * sp.normal.x + double(sp.normal.y) * sp.normal.y +
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
                const double w = std::max(k_pi * r * r, 1e-300) / copies[sp.point];
                sum.w += w;
                const double p[3] = {sp.position.x, sp.position.y, sp.position.z};
                const double nn[3] = {sp.normal.x, sp.normal.y, sp.normal.z};
                const double c[3] = {double(col.r), double(col.g), double(col.b)};
                for (int ax = 0; ax < 3; ++ax)
                    sum.p[ax] += w * p[ax], sum.n[ax] += w * nn[ax], sum.c[ax] += w * c[ax];
            }
            e.checksum = pool::checksum({base, static_cast<std::size_t>(e.size)});
            // the brick's LOD disc: its sphere holds every splat's disc
            pool::LodSplat disc = lod_from_sum(sum);
            double cover = 0;
            for (const pool::Splat* sp : brick_splats)
                cover = std::max(cover, distance(sp->position, disc.position) + sp->radius);
            disc.radius = round_up(cover);
            out.lod[e.top_node] = disc;
            sums[e.top_node] = sum;
            const std::uint64_t now = done.fetch_add(1) + 1;
            if (worker == 0 && params.progress) params.progress(now, bricks);
        }
    });
    if (params.progress) params.progress(bricks, bricks);

    // 4. LOD discs of the internal top nodes, children first (they come after their parent)
    for (std::size_t t = top_count; t-- > 0;) {
        const std::uint32_t w = out.top_nodes[t];
        if (pool::node_type(w) != NodeType::internal) continue;
        const std::uint32_t a = pool::node_address(w);
        LodSum sum;
        for (std::uint32_t c = 0; c < 8; ++c) sum.add(sums[a + c]);
        pool::LodSplat disc = lod_from_sum(sum);
        double cover = 0;
        for (std::uint32_t c = 0; c < 8; ++c)
            if (out.lod[a + c].radius > 0)
                cover =
                    std::max(cover, distance(out.lod[a + c].position, disc.position) + out.lod[a + c].radius);
        disc.radius = round_up(cover);
        out.lod[t] = disc;
        sums[t] = sum;
    }

    pool::BrickInfo& info = out.info;
    for (int ax = 0; ax < 3; ++ax) info.root_min[ax] = oi.root_min[ax];
    info.root_size = oi.root_size;
    info.depth = oi.depth;
    info.brick_count = std::uint32_t(bricks);
    info.top_node_count = std::uint32_t(top_count);
    info.brick_splat_limit = limit;
    info.flags = (colors.empty() ? 0u : pool::k_bricks_colors) |
                 ((oi.flags & pool::k_octree_culled) ? pool::k_bricks_culled : 0u) |
                 ((oi.flags & pool::k_octree_replicated) ? pool::k_bricks_replicated : 0u);
    info.unique_splats = oi.unique_splats;
    BrickStats stats;
    stats.bricks = info.brick_count;
    stats.top_nodes = info.top_node_count;
    stats.top_depth = *std::max_element(level.begin(), level.end());
    stats.min_brick_splats = bricks ? 0xFFFFFFFFu : 0;
    for (const pool::BrickEntry& e : out.table) {
        info.splat_count += e.splat_count;
        info.max_brick_splats = std::max(info.max_brick_splats, e.splat_count);
        stats.min_brick_splats = std::min(stats.min_brick_splats, e.splat_count);
    }
    stats.max_brick_splats = info.max_brick_splats;
    stats.splats = info.splat_count;
    stats.data_bytes = out.data.size();
    for (const CodecError& e : errors) stats.error.merge(e);
    stats.seconds = tool::now_seconds() - start;
    if (stats_out) *stats_out = stats;
    return out;
}

void add_brick_sections(BrickedOctree bricks, pool::PoolWriter& writer) {
    writer.add_array(pool::SectionType::brick_info, std::vector<pool::BrickInfo>{bricks.info});
    writer.add_array(pool::SectionType::brick_top_nodes, std::move(bricks.top_nodes));
    writer.add_array(pool::SectionType::brick_table, std::move(bricks.table));
    writer.add_array(pool::SectionType::brick_data, std::move(bricks.data));
    writer.add_array(pool::SectionType::lod_splats, std::move(bricks.lod));
}

}  // namespace prt::pre
