// PointRT preprocess: bricks straight from points, out of core (bricks_from_points.h, issue 17).
//
// Why the cells give the whole octree's bricks: build_octree decides a node's split from the splats
// overlapping it (thesis 3.2) and puts a splat in every child its disk overlaps (thesis 3.4), so the
// subtree below a node depends only on the splats overlapping that node, in their input order;
// culling decides a leaf's replicas from probes that depend only on the leaf (its cell, its splats,
// its octree-wide index: core/cull.h); the brick cut decides a node from its own subtree's size.
// So once the partition's cells are nodes that the whole build splits down to, each cell's subtree,
// culled and cut, is exactly that part of the whole result.
//
//   1. bounds    one pass: the root cube (RootBounds, build_octree's) and the usable points
//   2. histogram one pass: centres per cell of level k_histogram_level (Morton order)
//   3. partition from the root, split a cell while it holds more than a cell's worth of points
//                (estimated from the histogram); an inner cell must hold more than 2 x brick_splats
//                centres, so the whole cut makes it an inner top node (culling keeps every centre)
//   4. count     one pass: each point classified down the partition as build_octree classifies it
//                (child_overlap_mask), counting points per cell and chunk; each inner cell's exact
//                count and radius sum checks that build_octree splits it (octree_splits_node)
//   5. scatter   one pass: each point's record into its cells' ranges of a spill file, in input
//                order within each cell (chunks write disjoint ranges, so in parallel)
//   6. cells     in depth-first (Morton) order: build_octree_cell, cull_octree over the part (its
//                first leaf's octree-wide index: the leaves of earlier cells), build_brick_part; the
//                payloads appended to a spill file
//   7. assemble  the top tree breadth first over the partition and the cells' top trees (the
//                numbering cut_top_tree gives), the table in that brick order, the payloads copied into
//                place, the LOD discs above the bricks (finish_bricks)
#include "bricks_from_points.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "morton.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool.h"

namespace prt::pre {

namespace {

constexpr std::uint32_t k_histogram_level = 6;  // 262144 cells
constexpr std::size_t k_chunk = std::size_t(1) << 20;
constexpr std::uint32_t k_no_cell = 0xFFFFFFFFu;

/// One point as a cell's build reads it.
struct Record {
    pool::Float3 position;
    pool::Float3 normal;
    float radius;
    pool::Rgba8 color;
};
static_assert(sizeof(Record) == 32);

/// A node of the partition: inner (8 children from `first`) or a cell (`cell` index, in
/// depth-first order).
struct PartNode {
    NodeCell at;
    std::uint32_t first = 0;  // inner: index of the first child
    std::uint32_t cell = k_no_cell;
    std::uint64_t centres = 0;  // centres in it (step 2's histogram)
    std::uint64_t count = 0;    // inner: points overlapping it (step 4)
    double radius_sum = 0;
};

std::uint32_t fine_coordinate(double c, double root_min, double scale) {
    const double q = std::floor((c - root_min) * scale);
    return static_cast<std::uint32_t>(std::clamp(q, 0.0, double((1u << k_histogram_level) - 1)));
}

class Partitioner {
public:
    Partitioner(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                std::span<const float> radii, std::span<const pool::Rgba8> colors,
                const PointBrickParams& params)
        : m_positions(positions),
          m_normals(normals),
          m_radii(radii),
          m_colors(colors),
          m_params(params),
          m_threads(resolve_threads(params.threads)) {}

    PointBricks run(PointBrickStats& stats) {
        const double start = tool::now_seconds();
        bounds(stats);           // 1
        partition(histogram());  // 2, 3
        count();                 // 4
        scatter();               // 5
        const double cells = tool::now_seconds();
        stats.partition_seconds = cells - start;
        build_cells(stats);  // 6
        const double assembly = tool::now_seconds();
        PointBricks out = assemble(stats);  // 7
        stats.seconds = tool::now_seconds() - start;
        stats.assemble_seconds = stats.seconds - (assembly - start);
        return out;
    }

private:
    /// Unmaps the input's pages of points [b, e) when the input is a file mapping, so that the passes
    /// over a model larger than memory keep the resident set bounded (spill_file.h drop_pages).
    void drop_input(std::size_t b, std::size_t e) const {
        if (!m_params.input_mapped) return;
        drop_pages(m_positions.data() + b, (e - b) * sizeof(pool::Float3));
        drop_pages(m_normals.data() + b, (e - b) * sizeof(pool::Float3));
        drop_pages(m_radii.data() + b, (e - b) * sizeof(float));
        if (!m_colors.empty()) drop_pages(m_colors.data() + b, (e - b) * sizeof(pool::Rgba8));
    }

    void report(const char* stage, std::uint64_t done, std::uint64_t total) const {
        if (m_params.progress) m_params.progress(stage, done, total);
    }

    // -- 1 ----------------------------------------------------------------------------------------
    void bounds(PointBrickStats& stats) {
        const std::size_t n = m_positions.size();
        if (m_normals.size() != n || m_radii.size() != n || (!m_colors.empty() && m_colors.size() != n))
            throw Error("bricks from points: " + std::to_string(n) + " positions but " +
                        std::to_string(m_normals.size()) + " normals, " + std::to_string(m_radii.size()) +
                        " radii and " + std::to_string(m_colors.size()) + " colours");
        if (n > std::numeric_limits<std::uint32_t>::max())
            throw Error("bricks from points: more than 2^32 - 1 points");
        std::vector<RootBounds> per(m_threads);
        parallel_chunks(n, k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned w) {
            for (std::size_t i = b; i < e; ++i) per[w].add(m_positions[i], m_normals[i], m_radii[i]);
            drop_input(b, e);
        });
        RootBounds all;
        for (const RootBounds& r : per) all.merge(r);
        m_root = all.root();
        stats.points = all.valid();
        stats.skipped = all.skipped();
        m_chunks = (n + k_chunk - 1) / k_chunk;
    }

    // -- 2 ----------------------------------------------------------------------------------------
    /// Centres per fine cell, as prefix sums over Morton order (entry m: centres in cells < m).
    std::vector<std::uint64_t> histogram() const {
        const std::size_t cells = std::size_t(1) << (3 * k_histogram_level);
        std::vector<std::vector<std::uint32_t>> per(m_threads, std::vector<std::uint32_t>(cells, 0));
        const double scale = double(1u << k_histogram_level) / double(m_root.root_size);
        parallel_chunks(m_positions.size(), k_chunk, m_threads,
                        [&](std::size_t b, std::size_t e, unsigned w) {
                            for (std::size_t i = b; i < e; ++i) {
                                if (!usable(i)) continue;
                                const pool::Float3 p = m_positions[i];
                                ++per[w][morton3(fine_coordinate(p.x, m_root.root_min[0], scale),
                                                 fine_coordinate(p.y, m_root.root_min[1], scale),
                                                 fine_coordinate(p.z, m_root.root_min[2], scale))];
                            }
                            drop_input(b, e);
                        });
        std::vector<std::uint64_t> prefix(cells + 1, 0);
        for (std::size_t m = 0; m < cells; ++m) {
            std::uint64_t sum = 0;
            for (const auto& h : per) sum += h[m];
            prefix[m + 1] = prefix[m] + sum;
        }
        return prefix;
    }

    bool usable(std::size_t i) const { return octree_uses_point(m_positions[i], m_normals[i], m_radii[i]); }

    // -- 3 ----------------------------------------------------------------------------------------
    void partition(const std::vector<std::uint64_t>& prefix) {
        const std::uint64_t capacity =
            m_params.cell_points > 0
                ? m_params.cell_points
                : std::max<std::uint64_t>(m_params.memory / k_cell_bytes_per_point, 1u << 16);
        const std::uint64_t min_inner =
            2 * std::uint64_t(std::max<std::uint32_t>(m_params.bricks.brick_splats, 1));
        auto centres = [&](const NodeCell& c) -> std::uint64_t {
            if (c.level > k_histogram_level) return 0;
            const std::uint32_t shift = 3 * (k_histogram_level - c.level);
            const std::uint64_t m = morton3(c.cell[0], c.cell[1], c.cell[2]);
            return prefix[(m + 1) << shift] - prefix[m << shift];
        };
        m_nodes.assign(1, PartNode{});
        // depth first, so cells are numbered in Morton order
        std::vector<std::uint32_t> stack{0};
        std::uint32_t cells = 0;
        while (!stack.empty()) {
            const std::uint32_t i = stack.back();
            stack.pop_back();
            const NodeCell at = m_nodes[i].at;
            const std::uint64_t c = centres(at);
            m_nodes[i].centres = c;
            if (at.level < k_histogram_level && at.level < m_params.octree.max_depth && c > capacity &&
                c > min_inner) {
                const std::uint32_t first = std::uint32_t(m_nodes.size());
                m_nodes[i].first = first;
                for (std::uint32_t k = 0; k < 8; ++k) {
                    PartNode child;
                    child.at.level = at.level + 1;
                    for (int a = 0; a < 3; ++a) child.at.cell[a] = 2 * at.cell[a] + ((k >> a) & 1u);
                    m_nodes.push_back(child);
                }
                for (std::uint32_t k = 8; k-- > 0;) stack.push_back(first + k);
            } else {
                m_nodes[i].cell = cells++;
                m_cell_nodes.push_back(i);
            }
        }
        m_cell_count.assign(std::size_t(cells) * m_chunks, 0);
    }

    bool inner(std::uint32_t i) const { return m_nodes[i].cell == k_no_cell; }

    /// Calls visit(cell) for each cell the point's splat goes to, accumulating inner nodes' counts
    /// into `counts` / `sums` (per node) when given.
    template <class Visit>
    void classify(std::size_t i, Visit&& visit, std::uint64_t* counts, double* sums) const {
        std::uint32_t stack[64];
        std::uint32_t top = 0;
        stack[top++] = 0;
        const bool replicate = m_params.octree.replicate;
        while (top > 0) {
            const std::uint32_t k = stack[--top];
            if (!inner(k)) {
                visit(m_nodes[k].cell);
                continue;
            }
            if (counts) ++counts[k], sums[k] += m_radii[i];
            const std::uint8_t mask = child_overlap_mask(m_root, m_nodes[k].at, m_positions[i], m_normals[i],
                                                         m_radii[i], replicate);
            for (std::uint32_t c = 8; c-- > 0;)  // children in order, depth first
                if (mask >> c & 1u) stack[top++] = m_nodes[k].first + c;
        }
    }

    // -- 4 ----------------------------------------------------------------------------------------
    void count() {
        const std::size_t nodes = m_nodes.size();
        const std::size_t cells = m_cell_nodes.size();
        std::vector<std::vector<std::uint64_t>> counts(m_threads, std::vector<std::uint64_t>(nodes, 0));
        std::vector<std::vector<double>> sums(m_threads, std::vector<double>(nodes, 0.0));
        std::atomic<std::uint64_t> done{0};
        parallel_chunks(
            m_positions.size(), k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned w) {
                std::uint64_t* row = m_cell_count.data() + (b / k_chunk) * cells;
                for (std::size_t i = b; i < e; ++i) {
                    if (!usable(i)) continue;
                    classify(
                        i, [&](std::uint32_t cell) { ++row[cell]; }, counts[w].data(), sums[w].data());
                }
                drop_input(b, e);
                const std::uint64_t d = done.fetch_add(e - b) + (e - b);
                if (w == 0) report("partitioning points", d, 2 * m_positions.size());
            });
        for (std::size_t k = 0; k < nodes; ++k) {
            if (!inner(std::uint32_t(k))) continue;
            for (unsigned w = 0; w < m_threads; ++w)
                m_nodes[k].count += counts[w][k], m_nodes[k].radius_sum += sums[w][k];
            // build_octree must split it: with a margin on the radius rule (the sums' order differs)
            OctreeParams strict = m_params.octree;
            strict.min_cell_ratio *= 2;
            if (!octree_splits_node(strict, m_root, m_nodes[k].at, m_nodes[k].count, m_nodes[k].radius_sum,
                                    m_nodes[k].centres))
                throw Error("bricks from points: octree cell (level " + std::to_string(m_nodes[k].at.level) +
                            ") holds " + std::to_string(m_nodes[k].count) +
                            " points but the octree would not split it; raise --memory");
        }
        // cell ranges: cell-major, chunks in order within a cell
        m_cell_begin.assign(cells + 1, 0);
        m_slot.assign(m_cell_count.size(), 0);
        std::uint64_t at = 0;
        for (std::size_t c = 0; c < cells; ++c) {
            m_cell_begin[c] = at;
            for (std::size_t j = 0; j < m_chunks; ++j) {
                m_slot[j * cells + c] = at;
                at += m_cell_count[j * cells + c];
            }
        }
        m_cell_begin[cells] = at;
    }

    // -- 5 ----------------------------------------------------------------------------------------
    void scatter() {
        const std::size_t cells = m_cell_nodes.size();
        const std::uint64_t records = m_cell_begin[cells];
        m_records = SpillFile(m_params.spill_folder, std::max<std::uint64_t>(records, 1) * sizeof(Record),
                              "the partitioned points");
        Record* out = m_records.as<Record>().data();
        std::atomic<std::uint64_t> done{0};
        parallel_chunks(
            m_positions.size(), k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned w) {
                std::uint64_t* slot = m_slot.data() + (b / k_chunk) * cells;
                const std::vector<std::uint64_t> first(slot, slot + cells);
                for (std::size_t i = b; i < e; ++i) {
                    if (!usable(i)) continue;
                    const Record r{m_positions[i], m_normals[i], m_radii[i],
                                   m_colors.empty() ? pool::Rgba8{255, 255, 255, 255} : m_colors[i]};
                    classify(
                        i, [&](std::uint32_t cell) { out[slot[cell]++] = r; }, nullptr, nullptr);
                }
                drop_input(b, e);
                // the records written stay in the spill file (shared mapping), not in the process
                for (std::size_t c = 0; c < cells; ++c)
                    drop_pages(out + first[c], (slot[c] - first[c]) * sizeof(Record));
                const std::uint64_t d = done.fetch_add(e - b) + (e - b);
                if (w == 0) report("partitioning points", m_positions.size() + d, 2 * m_positions.size());
            });
        std::vector<std::uint64_t>().swap(m_slot);
        std::vector<std::uint64_t>().swap(m_cell_count);
    }

    // -- 6 ----------------------------------------------------------------------------------------
    /// One cell's bricks, numbered within the cell, with its payload in m_payloads.
    struct CellBricks {
        std::vector<std::uint32_t> top_nodes;
        std::vector<pool::BrickEntry> table;  // offset: into m_payloads
        std::vector<pool::LodSplat> lod;
        std::vector<LodSum> sums;
        std::vector<pool::BrickLod> lod_table;  // first: into lod_nodes
        std::vector<std::uint32_t> lod_nodes;
        std::vector<pool::CompressedSplat> lod_discs;
    };

    void build_cells(PointBrickStats& stats) {
        const std::size_t cells = m_cell_nodes.size();
        m_payloads = AppendFile(m_params.spill_folder, "the brick payloads");
        m_cells.resize(cells);
        std::uint64_t leaf_base = 0;
        const std::uint64_t records_total = m_cell_begin[cells];
        for (std::size_t c = 0; c < cells; ++c) {
            const std::uint64_t b = m_cell_begin[c], e = m_cell_begin[c + 1];
            report("building cells", b, records_total);
            if (b == e) continue;
            const NodeCell at = m_nodes[m_cell_nodes[c]].at;
            stats.cells += 1;
            stats.partition_depth = std::max(stats.partition_depth, at.level);
            stats.max_cell_points = std::max(stats.max_cell_points, e - b);
            const std::span<const Record> recs = m_records.as<Record>().subspan(b, e - b);
            std::vector<pool::Float3> positions(recs.size()), normals(recs.size());
            std::vector<float> radii(recs.size());
            std::vector<pool::Rgba8> colors(m_colors.empty() ? 0 : recs.size());
            for (std::size_t k = 0; k < recs.size(); ++k) {
                positions[k] = recs[k].position;
                normals[k] = recs[k].normal;
                radii[k] = recs[k].radius;
                if (!colors.empty()) colors[k] = recs[k].color;
            }
            drop_pages(recs.data(), recs.size_bytes());
            double t0 = tool::now_seconds();
            OctreeParams op = m_params.octree;
            op.threads = m_threads;
            op.progress = nullptr;
            SplatOctree octree = build_octree_cell(positions, normals, radii, m_root, at, op);
            std::vector<pool::Float3>().swap(positions);
            std::vector<pool::Float3>().swap(normals);
            std::vector<float>().swap(radii);
            double t1 = tool::now_seconds();
            stats.octree_seconds += t1 - t0;
            m_depth = std::max(m_depth, octree.info.depth);
            stats.stored_splats += octree.splats.size();
            if (octree.leaf_info.size() - 1 + leaf_base > std::numeric_limits<std::uint32_t>::max())
                throw Error("bricks from points: more than 2^32 - 1 filled leaves");
            pool::SplatOctreeSections sections{octree.info, octree.nodes, octree.leaf_info, octree.splats};
            CulledOctree culled;
            if (m_params.cull) {
                CullParams cp = m_params.culling;
                cp.threads = m_threads;
                cp.progress = nullptr;
                culled = cull_octree(sections, cp, nullptr, OctreePart{at, std::uint32_t(leaf_base)});
                std::vector<pool::Splat>().swap(octree.splats);
                sections =
                    pool::SplatOctreeSections{culled.info, octree.nodes, culled.leaf_info, culled.splats};
            }
            stats.culled_splats += sections.splats.size();
            t0 = tool::now_seconds();
            stats.cull_seconds += t0 - t1;
            leaf_base += octree.info.filled_leaves;
            BrickParams bp = m_params.bricks;
            bp.threads = m_threads;
            bp.progress = nullptr;
            BrickPart part = build_brick_part(sections, colors, bp, at);
            m_error.merge(part.error);
            m_top_depth = std::max(m_top_depth, part.top_depth);
            const std::uint64_t base = m_payloads.append(part.bricks.data.data(), part.bricks.data.size());
            for (pool::BrickEntry& entry : part.bricks.table) entry.offset += base;
            stats.brick_seconds += tool::now_seconds() - t0;
            m_cells[c] = CellBricks{std::move(part.bricks.top_nodes), std::move(part.bricks.table),
                                    std::move(part.bricks.lod),       std::move(part.sums),
                                    std::move(part.bricks.lod_table), std::move(part.bricks.lod_nodes),
                                    std::move(part.bricks.lod_discs)};
            stats.cell_records += e - b;
        }
        report("building cells", records_total, records_total);
        m_records = SpillFile{};
    }

    // -- 7 ----------------------------------------------------------------------------------------
    PointBricks assemble(PointBrickStats& stats) {
        PointBricks out;
        BrickedOctree& br = out.bricks;
        std::vector<LodSum> sums;
        // Breadth first over the partition's inner nodes and the cells' top trees; an item is a
        // partition node (cell == k_no_cell) or (cell, its local top node).
        struct Item {
            std::uint32_t node, cell, local;
        };
        std::vector<Item> items{{0, k_no_cell, 0}};
        auto enter = [&](std::uint32_t node) {
            const PartNode& p = m_nodes[node];
            if (!inner(node)) return Item{node, p.cell, 0};
            return Item{node, k_no_cell, 0};
        };
        items[0] = enter(0);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> brick_src;  // (cell, local brick)
        for (std::size_t t = 0; t < items.size(); ++t) {
            const Item it = items[t];
            const std::uint32_t first = std::uint32_t(items.size());
            if (it.cell == k_no_cell) {
                br.top_nodes.push_back(pool::make_node(pool::NodeType::internal, first));
                br.lod.push_back(pool::LodSplat{});
                sums.push_back(LodSum{});
                for (std::uint32_t c = 0; c < 8; ++c) items.push_back(enter(m_nodes[it.node].first + c));
                continue;
            }
            const CellBricks& cb = m_cells[it.cell];
            if (cb.top_nodes.empty()) {  // a cell no point overlaps: an empty leaf
                br.top_nodes.push_back(pool::make_node(pool::NodeType::empty_leaf, 0));
                br.lod.push_back(pool::LodSplat{});
                sums.push_back(LodSum{});
                continue;
            }
            const std::uint32_t w = cb.top_nodes[it.local];
            br.lod.push_back(cb.lod[it.local]);
            sums.push_back(cb.sums[it.local]);
            switch (pool::node_type(w)) {
                case pool::NodeType::internal:
                    br.top_nodes.push_back(pool::make_node(pool::NodeType::internal, first));
                    for (std::uint32_t c = 0; c < 8; ++c)
                        items.push_back(Item{it.node, it.cell, pool::node_address(w) + c});
                    break;
                case pool::NodeType::brick:
                    br.top_nodes.push_back(
                        pool::make_node(pool::NodeType::brick, std::uint32_t(brick_src.size())));
                    brick_src.emplace_back(it.cell, pool::node_address(w));
                    break;
                default:
                    br.top_nodes.push_back(pool::make_node(pool::NodeType::empty_leaf, 0));
                    break;
            }
            if (std::uint64_t(items.size()) > pool::k_node_address_max)
                throw Error("the top tree exceeds 2^30 nodes");
        }
        // the table in brick order, payloads 64-byte aligned
        br.table.resize(brick_src.size());
        std::uint64_t offset = 0;
        for (std::size_t b = 0; b < brick_src.size(); ++b) {
            pool::BrickEntry e = m_cells[brick_src[b].first].table[brick_src[b].second];
            e.offset = offset;
            br.table[b] = e;
            offset +=
                (e.size + pool::k_brick_alignment - 1) / pool::k_brick_alignment * pool::k_brick_alignment;
        }
        if (m_params.bricks.lod_splats > 0) {  // the LOD prefixes in brick order
            br.lod_table.resize(brick_src.size());
            for (std::size_t b = 0; b < brick_src.size(); ++b) {
                const CellBricks& cb = m_cells[brick_src[b].first];
                pool::BrickLod l = cb.lod_table[brick_src[b].second];
                const auto nodes = std::span(cb.lod_nodes).subspan(l.first, l.node_count);
                const auto discs = std::span(cb.lod_discs).subspan(l.first, l.node_count);
                l.first = br.lod_nodes.size();
                br.lod_table[b] = l;
                br.lod_nodes.insert(br.lod_nodes.end(), nodes.begin(), nodes.end());
                br.lod_discs.insert(br.lod_discs.end(), discs.begin(), discs.end());
            }
        }
        for (std::size_t t = 0; t < br.top_nodes.size(); ++t)
            if (pool::node_type(br.top_nodes[t]) == pool::NodeType::brick)
                br.table[pool::node_address(br.top_nodes[t])].top_node = std::uint32_t(t);
        out.data = SpillFile(m_params.spill_folder, std::max<std::uint64_t>(offset, 1), "the brick payloads");
        out.data_bytes = offset;
        for (std::size_t b = 0; b < brick_src.size(); ++b) {
            const pool::BrickEntry& src = m_cells[brick_src[b].first].table[brick_src[b].second];
            m_payloads.read(src.offset, out.data.data() + br.table[b].offset, src.size);
            drop_pages(out.data.data() + br.table[b].offset, src.size);
            report("writing bricks", b + 1, brick_src.size());
        }
        m_payloads = AppendFile{};
        std::uint32_t top_depth = m_top_depth;
        for (const PartNode& p : m_nodes) top_depth = std::max(top_depth, p.at.level);
        pool::OctreeInfo info = m_root;
        info.depth = std::max(m_depth, top_depth);  // an empty cell is a leaf at its level
        info.unique_splats = stats.points;
        info.flags = (m_params.octree.replicate ? pool::k_octree_replicated : 0u) |
                     (m_params.cull ? pool::k_octree_culled : 0u);
        stats.bricks = finish_bricks(br, sums, info, top_depth, m_params.bricks, !m_colors.empty());
        stats.bricks.data_bytes = offset;
        stats.bricks.error = m_error;
        return out;
    }

    std::span<const pool::Float3> m_positions, m_normals;
    std::span<const float> m_radii;
    std::span<const pool::Rgba8> m_colors;
    const PointBrickParams& m_params;
    unsigned m_threads;
    pool::OctreeInfo m_root{};
    std::size_t m_chunks = 0;
    std::vector<PartNode> m_nodes;
    std::vector<std::uint32_t> m_cell_nodes;  // cell -> partition node
    std::vector<std::uint64_t> m_cell_count;  // [chunk][cell]
    std::vector<std::uint64_t> m_slot;        // [chunk][cell]: next record index
    std::vector<std::uint64_t> m_cell_begin;  // cell -> first record
    SpillFile m_records;
    AppendFile m_payloads;
    std::vector<CellBricks> m_cells;
    std::uint32_t m_depth = 0, m_top_depth = 0;
    CodecError m_error;
};

}  // namespace

PointBricks build_bricks_from_points(std::span<const pool::Float3> positions,
                                     std::span<const pool::Float3> normals, std::span<const float> radii,
                                     std::span<const pool::Rgba8> colors, const PointBrickParams& params,
                                     PointBrickStats* stats_out) {
    PointBrickStats stats;
    Partitioner partitioner(positions, normals, radii, colors, params);
    PointBricks out = partitioner.run(stats);
    stats.bricks.seconds = stats.seconds;
    if (stats_out) *stats_out = stats;
    return out;
}

}  // namespace prt::pre
