// PointRT preprocess: the splat octree builder (thesis 2.2, 3.1, 3.2, 3.4).
//
// Build plan:
//  1. Gather the splats with a finite positive radius; compute the root cube enclosing every disk.
//  2. Top phase (serial control, parallel classification): split nodes holding more than a task's
//     worth of splats, depth first, so that the remaining subtrees are independent tasks in Morton
//     (depth-first, Z-curve) order.
//  3. Build each task's subtree depth first on the worker threads into task-local arrays.
//  4. Lay the nodes out breadth first (thesis 2.2.3: level by level, so the first levels share the
//     cache), the 8 children of a node together in Morton order; number filled leaves and store
//     their splats in depth-first order (spatially adjacent leaves get adjacent data).
// With OctreeParams::backend "cuda", steps 2-4 run level by level on the GPU instead
// (runtime/cuda/src/octree_build.cu), with the same decisions (core/disk_box.h) and the same sections.
#include "octree_build.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <string>

#include "backend_choice.h"
#include "buffer.h"
#include "disk_box.h"
#include "float_round.h"
#include "morton.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"
#include "radix_sort.h"

#ifdef PRT_HAVE_CUDA
#include "prt/cuda/device.h"
#include "prt/cuda/octree_cuda.h"
#endif

namespace prt::pre {

namespace {

using pool::make_node;
using pool::NodeType;

constexpr std::uint32_t k_max_supported_depth = 30;  // cell coordinates fit 30 bits
constexpr std::uint32_t k_local_task_ref = 3;        // top-tree node type: "subtree built by task"

/// Bit c of the result is set when splat `s` belongs to child c of the node (level, cell)
/// (core/disk_box.h, disk_child_mask: the CUDA builder runs the same function).
std::uint8_t classify_splat(const BuildSplat& s, bool replicate, const double mid[3],
                            const double child_lo[8][3], const double child_hi[8][3]) {
    return core::disk_child_mask(s, replicate, mid, child_lo, child_hi);
}

/// The boxes of the 8 children of node (level, cell) (node_box()) and the node's mid-planes.
void child_cell_boxes(const pool::OctreeInfo& info, std::uint32_t level, const std::uint32_t cell[3],
                      double mid[3], double lo[8][3], double hi[8][3]) {
    for (unsigned child = 0; child < 8; ++child) {
        const std::uint32_t cc[3] = {2 * cell[0] + (child & 1u), 2 * cell[1] + (child >> 1 & 1u),
                                     2 * cell[2] + (child >> 2 & 1u)};
        node_box(info, level + 1, cc, lo[child], hi[child]);
    }
    for (int a = 0; a < 3; ++a) mid[a] = hi[0][a];  // child 0 is the lower half on every axis
}

/// A subtree under construction: nodes in local numbering (children of a node contiguous, the
/// internal nodes' address = local index of the first child), leaves in depth-first order.
struct LocalTree {
    std::vector<std::uint32_t> nodes;
    std::vector<std::uint32_t> leaf_begin;  // into ids
    std::vector<std::uint32_t> ids;         // splat indices, leaf-contiguous
    std::uint32_t depth = 0;
    std::uint64_t empty_leaves = 0;
    std::uint64_t max_leaf = 0;
    std::uint64_t reported_nodes = 0, reported_ids = 0;  // already added to the global counters
};

struct Task {
    std::uint32_t level = 0;
    std::uint32_t cell[3] = {0, 0, 0};
    std::vector<std::uint32_t> list;
    LocalTree tree;
};

/// Per-worker scratch: the stack of splat lists of the nodes on the current path, child masks.
struct Scratch {
    std::vector<std::uint32_t> stack;
    std::vector<std::uint8_t> masks;
};

class Builder {
public:
    Builder(pre::LargeVector<BuildSplat> splats, const pool::OctreeInfo& info, const OctreeParams& params,
            NodeCell root = {})
        : m_splats(std::move(splats)), m_info(info), m_params(params), m_root(root) {}

    /// Would a node at this level holding these splats be split (thesis 3.2: more than X)?
    bool should_split(std::uint32_t level, const std::uint32_t cell[3], const std::uint32_t* list,
                      std::size_t count) const {
        if (count <= m_params.max_leaf_splats || level >= m_params.max_depth) return false;
        std::uint64_t centres = count;
        if (m_params.split_by_centres && m_params.replicate) {
            // count only the centres in the node's half-open cell (the others are replicas)
            double lo[3], hi[3];
            node_box(m_info, level, cell, lo, hi);
            centres = 0;
            for (std::size_t k = 0; k < count; ++k) {
                const BuildSplat& s = m_splats[list[k]];
                bool inside = true;
                for (int a = 0; a < 3; ++a)
                    inside = inside && double(s.c[a]) >= lo[a] && double(s.c[a]) < hi[a];
                centres += inside;
            }
        }
        double sum = 0;
        if (m_params.min_cell_ratio > 0)
            for (std::size_t k = 0; k < count; ++k) sum += m_splats[list[k]].r;
        return octree_splits_node(m_params, m_info, NodeCell{level, {cell[0], cell[1], cell[2]}}, count, sum,
                                  centres);
    }

    std::uint8_t classify(const BuildSplat& s, const double mid[3], const double child_lo[8][3],
                          const double child_hi[8][3]) const {
        return classify_splat(s, m_params.replicate, mid, child_lo, child_hi);
    }

    void child_boxes(std::uint32_t level, const std::uint32_t cell[3], double mid[3], double lo[8][3],
                     double hi[8][3]) const {
        child_cell_boxes(m_info, level, cell, mid, lo, hi);
    }

    /// Emits a leaf for list[0, count): splats whose centre lies in the leaf's closed box first
    /// (the leaf's "original" splats, thesis 3.4), then the replicas, each group in Morton order
    /// of the centres (ties in input order).
    void emit_leaf(LocalTree& out, std::uint32_t node, std::uint32_t level, const std::uint32_t cell[3],
                   const std::uint32_t* list, std::size_t count) const {
        out.depth = std::max(out.depth, level);
        if (count == 0) {
            out.nodes[node] = make_node(NodeType::empty_leaf, 0);
            ++out.empty_leaves;
            return;
        }
        double lo[3], hi[3];
        node_box(m_info, level, cell, lo, hi);
        const std::uint32_t leaf = static_cast<std::uint32_t>(out.leaf_begin.size());
        out.leaf_begin.push_back(static_cast<std::uint32_t>(out.ids.size()));
        auto centre_inside = [&](std::uint32_t id) {
            const BuildSplat& s = m_splats[id];
            for (int a = 0; a < 3; ++a)
                if (!(double(s.c[a]) >= lo[a] && double(s.c[a]) <= hi[a])) return false;
            return true;
        };
        for (std::size_t k = 0; k < count; ++k)
            if (centre_inside(list[k])) out.ids.push_back(list[k]);
        for (std::size_t k = 0; k < count; ++k)
            if (!centre_inside(list[k])) out.ids.push_back(list[k]);
        out.max_leaf = std::max<std::uint64_t>(out.max_leaf, count);
        out.nodes[node] = make_node(NodeType::filled_leaf, leaf);
    }

    /// Splits list[b, e) of scratch.stack into the 8 children's lists, appended to the stack in
    /// child order; returns the children's [begin, end) offsets.
    void split_lists(Scratch& s, std::size_t b, std::size_t e, std::uint32_t level,
                     const std::uint32_t cell[3], std::size_t child_begin[8],
                     std::size_t child_end[8]) const {
        double mid[3], lo[8][3], hi[8][3];
        child_boxes(level, cell, mid, lo, hi);
        const std::size_t count = e - b;
        if (s.masks.size() < count) s.masks.resize(count);
        const std::size_t parallel_min = 1u << 16;
        if (count >= parallel_min && m_threads > 1 && m_top_phase) {
            parallel_chunks(count, 1u << 14, m_threads, [&](std::size_t cb, std::size_t ce, unsigned) {
                for (std::size_t k = cb; k < ce; ++k)
                    s.masks[k] = classify(m_splats[s.stack[b + k]], mid, lo, hi);
            });
        } else {
            for (std::size_t k = 0; k < count; ++k)
                s.masks[k] = classify(m_splats[s.stack[b + k]], mid, lo, hi);
        }
        std::size_t counts[8] = {};
        for (std::size_t k = 0; k < count; ++k)
            for (unsigned m = s.masks[k]; m; m &= m - 1) ++counts[__builtin_ctz(m)];
        const std::size_t base = s.stack.size();
        std::size_t total = 0;
        for (int c = 0; c < 8; ++c) {
            child_begin[c] = base + total;
            total += counts[c];
            child_end[c] = base + total;
        }
        s.stack.resize(base + total);
        std::size_t fill[8];
        std::copy(child_begin, child_begin + 8, fill);
        for (std::size_t k = 0; k < count; ++k) {
            const std::uint32_t id = s.stack[b + k];
            for (unsigned m = s.masks[k]; m; m &= m - 1) s.stack[fill[__builtin_ctz(m)]++] = id;
        }
    }

    /// Builds the subtree of local node `node` (already allocated) depth first.
    void build(LocalTree& out, Scratch& s, std::uint32_t node, std::uint32_t level,
               const std::uint32_t cell[3], std::size_t b, std::size_t e) {
        const std::size_t count = e - b;
        if (!should_split(level, cell, s.stack.data() + b, count)) {
            emit_leaf(out, node, level, cell, s.stack.data() + b, count);
            report(out, false);
            return;
        }
        split_node(out, s, node, level, cell, b, e,
                   [&](std::uint32_t child, const std::uint32_t child_cell[3], std::size_t cb,
                       std::size_t ce) { build(out, s, child, level + 1, child_cell, cb, ce); });
    }

    /// Splits node `node` of `out` (at `level`, over splat lists [b, e) of `s`): allocates its 8
    /// children, makes it internal and calls `child(index, cell, begin, end)` on each child in
    /// order (depth first), the child's list on top of the stack.
    template <class Child>
    void split_node(LocalTree& out, Scratch& s, std::uint32_t node, std::uint32_t level,
                    const std::uint32_t cell[3], std::size_t b, std::size_t e, Child&& child) {
        std::size_t cb[8], ce[8];
        split_lists(s, b, e, level, cell, cb, ce);
        const std::size_t first = out.nodes.size();
        out.nodes.resize(first + 8);
        out.nodes[node] = make_node(NodeType::internal, static_cast<std::uint32_t>(first));
        report(out, false);
        const std::size_t mark = cb[0];
        for (unsigned c = 0; c < 8; ++c) {
            const std::uint32_t cc[3] = {2 * cell[0] + (c & 1u), 2 * cell[1] + (c >> 1 & 1u),
                                         2 * cell[2] + (c >> 2 & 1u)};
            child(static_cast<std::uint32_t>(first + c), cc, cb[c], ce[c]);
        }
        s.stack.resize(mark);
    }

    /// Adds a subtree's growth to the global counters every so often and checks the encodable
    /// limits, so that an oversized tree fails early instead of exhausting memory.
    void report(LocalTree& out, bool final) {
        const std::uint64_t dn = out.nodes.size() - out.reported_nodes;
        const std::uint64_t di = out.ids.size() - out.reported_ids;
        if (!final && dn < (1u << 16) && di < (1u << 20)) return;
        out.reported_nodes = out.nodes.size();
        out.reported_ids = out.ids.size();
        const std::uint64_t nodes = m_global_nodes.fetch_add(dn) + dn;
        const std::uint64_t ids = m_global_ids.fetch_add(di) + di;
        check_octree_limits(nodes, 0, ids);
    }

    /// Top phase: splits large nodes (depth first) and turns every other node into a task.
    void build_top(Scratch& s, std::uint32_t node, std::uint32_t level, const std::uint32_t cell[3],
                   std::size_t b, std::size_t e, std::size_t task_threshold) {
        const std::size_t count = e - b;
        if (count <= task_threshold || !should_split(level, cell, s.stack.data() + b, count)) {
            Task task;
            task.level = level;
            std::copy(cell, cell + 3, task.cell);
            task.list.assign(s.stack.begin() + static_cast<std::ptrdiff_t>(b),
                             s.stack.begin() + static_cast<std::ptrdiff_t>(e));
            m_top.nodes[node] =
                (k_local_task_ref << pool::k_node_address_bits) | static_cast<std::uint32_t>(m_tasks.size());
            m_tasks.push_back(std::move(task));
            return;
        }
        m_top.depth = std::max(m_top.depth, level);
        split_node(
            m_top, s, node, level, cell, b, e,
            [&](std::uint32_t child, const std::uint32_t child_cell[3], std::size_t cb, std::size_t ce) {
                build_top(s, child, level + 1, child_cell, cb, ce, task_threshold);
            });
    }

    SplatOctree run(unsigned threads, OctreeStats& stats) {
        m_threads = threads;
        const std::size_t n = m_splats.size();
        // -- top phase --------------------------------------------------------------------------
        Scratch top_scratch;
        top_scratch.stack.resize(n);
        std::iota(top_scratch.stack.begin(), top_scratch.stack.end(), 0u);
        const std::size_t task_threshold = std::max<std::size_t>(2048, n / (std::size_t(threads) * 32));
        m_top.nodes.resize(1);
        m_top.depth = m_root.level;
        m_top_phase = true;
        build_top(top_scratch, 0, m_root.level, m_root.cell, 0, n, task_threshold);
        m_top_phase = false;
        top_scratch = Scratch{};

        // -- subtrees, largest first for load balance -------------------------------------------
        std::vector<std::size_t> order(m_tasks.size());
        std::iota(order.begin(), order.end(), std::size_t(0));
        std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            return m_tasks[a].list.size() > m_tasks[b].list.size();
        });
        std::vector<Scratch> scratch(threads);
        std::uint64_t task_total = 0;
        for (const Task& t : m_tasks) task_total += t.list.size();
        std::atomic<std::uint64_t> task_done{0};
        parallel_chunks(order.size(), 1, threads, [&](std::size_t tb, std::size_t te, unsigned worker) {
            for (std::size_t k = tb; k < te; ++k) {
                Task& task = m_tasks[order[k]];
                Scratch& s = scratch[worker];
                const std::uint64_t size = task.list.size();
                s.stack.assign(task.list.begin(), task.list.end());
                std::vector<std::uint32_t>().swap(task.list);
                task.tree.nodes.resize(1);
                build(task.tree, s, 0, task.level, task.cell, 0, s.stack.size());
                report(task.tree, true);
                const std::uint64_t done = task_done.fetch_add(size) + size;
                if (worker == 0 && m_params.progress) m_params.progress(done, task_total);
            }
        });
        scratch.clear();
        return assemble(threads, stats);
    }

private:
    SplatOctree assemble(unsigned threads, OctreeStats& stats) {
        const std::size_t task_count = m_tasks.size();
        std::vector<std::uint64_t> leaf_base(task_count + 1, 0), id_base(task_count + 1, 0);
        std::uint64_t nodes_total = m_top.nodes.size() - task_count;  // placeholders become task roots
        std::uint32_t depth = m_top.depth;
        std::uint64_t empty = 0, max_leaf = 0;
        for (std::size_t t = 0; t < task_count; ++t) {
            const LocalTree& tree = m_tasks[t].tree;
            leaf_base[t + 1] = leaf_base[t] + tree.leaf_begin.size();
            id_base[t + 1] = id_base[t] + tree.ids.size();
            nodes_total += tree.nodes.size();
            depth = std::max(depth, tree.depth);
            empty += tree.empty_leaves;
            max_leaf = std::max(max_leaf, tree.max_leaf);
        }
        const std::uint64_t filled = leaf_base[task_count];
        const std::uint64_t stored = id_base[task_count];
        check_octree_limits(nodes_total, filled, stored);

        SplatOctree octree;
        // -- nodes, breadth first (thesis 2.2.3), children together in Morton order ---------------
        struct Handle {
            std::uint32_t tree;  // 0 = top tree, t + 1 = task t
            std::uint32_t index;
        };
        auto resolve = [&](Handle h) {
            if (h.tree == 0 && (m_top.nodes[h.index] >> pool::k_node_address_bits) == k_local_task_ref)
                return Handle{pool::node_address(m_top.nodes[h.index]) + 1, 0};
            return h;
        };
        pre::reserve_on_huge_pages(octree.nodes, nodes_total);
        std::vector<Handle> level_nodes{resolve(Handle{0, 0})}, next;
        while (!level_nodes.empty()) {
            next.clear();
            const std::uint64_t next_level_start = octree.nodes.size() + level_nodes.size();
            for (const Handle h : level_nodes) {
                const LocalTree& tree = h.tree == 0 ? m_top : m_tasks[h.tree - 1].tree;
                const std::uint32_t local = tree.nodes[h.index];
                switch (pool::node_type(local)) {
                    case NodeType::internal: {
                        const std::uint64_t address = next_level_start + next.size();
                        octree.nodes.push_back(
                            make_node(NodeType::internal, static_cast<std::uint32_t>(address)));
                        const std::uint32_t first = pool::node_address(local);
                        for (std::uint32_t c = 0; c < 8; ++c)
                            next.push_back(resolve(Handle{h.tree, first + c}));
                        break;
                    }
                    case NodeType::filled_leaf: {
                        const std::uint64_t leaf = leaf_base[h.tree - 1] + pool::node_address(local);
                        octree.nodes.push_back(
                            make_node(NodeType::filled_leaf, static_cast<std::uint32_t>(leaf)));
                        break;
                    }
                    default:
                        octree.nodes.push_back(make_node(NodeType::empty_leaf, 0));
                        break;
                }
            }
            std::swap(level_nodes, next);
        }

        // -- leaf ranges and leaf-contiguous splats (depth-first leaf order) ---------------------
        // SplatOctree's vectors zero their elements on this thread, on huge pages the workers
        // touched first (buffer.h, prefault).
        pre::resize_on_huge_pages(octree.leaf_info, filled + 1, threads);
        pre::resize_on_huge_pages(octree.splats, stored, threads);
        parallel_chunks(task_count, 1, threads, [&](std::size_t tb, std::size_t te, unsigned) {
            for (std::size_t t = tb; t < te; ++t) {
                LocalTree& tree = m_tasks[t].tree;
                for (std::size_t j = 0; j < tree.leaf_begin.size(); ++j)
                    octree.leaf_info[leaf_base[t] + j] =
                        static_cast<std::uint32_t>(id_base[t] + tree.leaf_begin[j]);
                pool::Splat* out = octree.splats.data() + id_base[t];
                for (const std::uint32_t id : tree.ids) {
                    const BuildSplat& s = m_splats[id];
                    *out++ = pool::Splat{{s.c[0], s.c[1], s.c[2]}, s.r, {s.n[0], s.n[1], s.n[2]}, s.point};
                }
                tree = LocalTree{};
            }
        });
        octree.leaf_info[filled] = static_cast<std::uint32_t>(stored);

        describe_octree(octree, m_info, m_params, m_splats.size(), depth, empty, max_leaf, stats);
        return octree;
    }

    pre::LargeVector<BuildSplat> m_splats;
    pool::OctreeInfo m_info;
    OctreeParams m_params;
    NodeCell m_root;  // the node the tree is built from (the octree's root, or one cell of it)
    unsigned m_threads = 1;
    bool m_top_phase = false;  // only the (serial) top phase classifies large lists in parallel
    LocalTree m_top;
    std::vector<Task> m_tasks;
    std::atomic<std::uint64_t> m_global_nodes{1};
    std::atomic<std::uint64_t> m_global_ids{0};
};

}  // namespace

bool octree_splits_node(const OctreeParams& params, const pool::OctreeInfo& info, NodeCell node,
                        std::uint64_t count, double radius_sum, std::uint64_t centres) {
    if (count <= params.max_leaf_splats || node.level >= params.max_depth) return false;
    if (params.split_by_centres && params.replicate && centres <= params.max_leaf_splats) return false;
    if (params.min_cell_ratio > 0) {
        const double edge = double(info.root_size) / double(std::uint64_t(1) << node.level);
        if (edge < double(params.min_cell_ratio) * (radius_sum / double(count))) return false;
    }
    return true;
}

void check_octree_limits(std::uint64_t nodes, std::uint64_t filled_leaves, std::uint64_t stored_splats) {
    const std::uint64_t max_nodes = std::uint64_t(pool::k_node_address_max) + 1;  // child address <= 2^30 - 8
    if (nodes > max_nodes)
        throw Error("octree too large: " + std::to_string(nodes) +
                    " nodes exceed the 30-bit node address range (" + std::to_string(max_nodes) +
                    "); raise --leaf-size or lower --max-depth");
    if (filled_leaves > max_nodes)
        throw Error("octree too large: " + std::to_string(filled_leaves) +
                    " filled leaves exceed the 30-bit leaf address range (" + std::to_string(max_nodes) +
                    "); raise --leaf-size or lower --max-depth");
    if (stored_splats > std::numeric_limits<std::uint32_t>::max())
        throw Error(
            "octree too large: " + std::to_string(stored_splats) +
            " stored splats exceed the 32-bit leaf_info range; raise --leaf-size or use --no-replicate");
}

void node_box(const pool::OctreeInfo& info, std::uint32_t level, const std::uint32_t cell[3], double lo[3],
              double hi[3]) {
    core::octree_node_box(info.root_min, info.root_size, level, cell, lo, hi);
}

namespace {

// thesis 3.1: a point's usability and build record (prt/core/disk_box.h, shared with the GPU).
using core::make_build_splat;
using core::usable_build_point;

void check_params(const OctreeParams& params, std::size_t points) {
    if (params.max_leaf_splats == 0) throw Error("octree build: the leaf size (X) must be at least 1");
    if (params.max_depth > k_max_supported_depth)
        throw Error("octree build: maximum depth " + std::to_string(params.max_depth) + " exceeds " +
                    std::to_string(k_max_supported_depth));
    if (!(params.min_cell_ratio >= 0) || !std::isfinite(params.min_cell_ratio))
        throw Error("octree build: the minimum cell ratio must be finite and >= 0");
    if (points > std::numeric_limits<std::uint32_t>::max())
        throw Error("octree build: more than 2^32 - 1 points");
}

/// The usable points as build records (point = index in the arrays), skipped ones counted.
pre::LargeVector<BuildSplat> build_splats(std::span<const pool::Float3> positions,
                                     std::span<const pool::Float3> normals, std::span<const float> radii,
                                     OctreeStats& stats, RootBounds* bounds, unsigned threads) {
    if (normals.size() != positions.size() || radii.size() != positions.size())
        throw Error("octree build: " + std::to_string(positions.size()) + " positions but " +
                    std::to_string(normals.size()) + " normals and " + std::to_string(radii.size()) +
                    " radii");
    // In parallel, in input order (parallel_select): the usable points' records, then the root
    // cube's bounds per worker, merged (min and max: the same whatever the split).
    const std::size_t n = positions.size();
    auto usable = [&](std::size_t i) {
        double len;
        return usable_build_point(positions[i], normals[i], radii[i], len);
    };
    pre::LargeVector<BuildSplat> splats;
    pre::resize_prefaulted(splats, n, threads);
    const std::size_t kept = parallel_select(n, threads, usable, [&](std::size_t rank, std::size_t i) {
        double len;
        usable_build_point(positions[i], normals[i], radii[i], len);
        splats[rank] = make_build_splat(positions[i], normals[i], radii[i], len, static_cast<std::uint32_t>(i));
    });
    splats.resize(kept);
    stats.skipped_splats += n - kept;
    if (bounds) {
        std::vector<RootBounds> part(std::max(threads, 1u));
        parallel_chunks(n, 1u << 16, threads, [&](std::size_t b, std::size_t e, unsigned worker) {
            for (std::size_t i = b; i < e; ++i)
                if (usable(i)) part[worker].add(positions[i], normals[i], radii[i]);
        });
        for (const RootBounds& p : part) bounds->merge(p);
    }
    if (splats.empty())
        throw Error("octree build: no point has a finite positive radius and a normal (" +
                    std::to_string(positions.size()) + " points)");
    return splats;
}

/// Morton (Z-curve) order of the centres: the builder's lists then touch nearby memory, whatever
/// the input order (a random-order input otherwise makes every access a cache miss). Ties keep
/// the input order, so the result does not depend on the thread count, and a subset of the
/// points (one cell of an out-of-core build) keeps the order it has among all of them.
void sort_by_morton(pre::LargeVector<BuildSplat>& splats, const pool::OctreeInfo& info, unsigned threads) {
    struct MortonKey {
        std::uint64_t key;
        std::uint32_t index;
    };
    pre::Buffer<MortonKey> keys(splats.size());  // first touched by the workers
    const double scale = core::build_splat_morton_scale(info.root_size);
    parallel_chunks(splats.size(), 1u << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i)
            keys[i] = MortonKey{core::build_splat_morton_key(splats[i].c, info.root_min, scale),
                                static_cast<std::uint32_t>(i)};
    });
    // Stable by key on pairs made in index order: the order std::sort of the pairs gives.
    pre::radix_sort_by(keys, 63, threads, [](const MortonKey& k) { return k.key; });
    pre::LargeVector<BuildSplat> sorted;
    pre::resize_prefaulted(sorted, splats.size(), threads);
    parallel_chunks(splats.size(), 1u << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) sorted[i] = splats[keys[i].index];
    });
    splats = std::move(sorted);
}

/// The tree below `cell` over Morton-sorted build records, on the CPU (Builder) or on the GPU
/// (prt/cuda/octree_cuda.h), which gives the same sections.
SplatOctree build_sorted(pre::LargeVector<BuildSplat> splats, const pool::OctreeInfo& info, NodeCell cell,
                         const OctreeParams& params, unsigned threads, OctreeStats& stats) {
    if (resolve_octree_backend(params.backend) == "cpu") {
        Builder builder(std::move(splats), info, params, cell);
        return builder.run(threads, stats);
    }
#ifdef PRT_HAVE_CUDA
    cuda::OctreeCudaParams cp;
    cp.max_leaf_splats = params.max_leaf_splats;
    cp.max_depth = params.max_depth;
    cp.replicate = params.replicate;
    cp.min_cell_ratio = params.min_cell_ratio;
    cp.split_by_centres = params.split_by_centres;
    cuda::OctreeCudaResult r;
    cuda::build_octree_cuda(std::span<const BuildSplat>(splats.data(), splats.size()), info.root_min,
                            info.root_size, cell.level, cell.cell, cp, check_octree_limits, r);
    SplatOctree octree;
    octree.nodes = std::move(r.nodes);
    octree.leaf_info = std::move(r.leaf_info);
    octree.splats = std::move(r.splats);
    describe_octree(octree, info, params, splats.size(), r.depth, r.empty_leaves, r.max_leaf, stats);
    return octree;
#else
    throw Error("octree build: this build has no CUDA backend");
#endif
}

}  // namespace

void describe_octree(SplatOctree& octree, const pool::OctreeInfo& root, const OctreeParams& params,
                     std::uint64_t unique, std::uint32_t depth, std::uint64_t empty, std::uint64_t max_leaf,
                     OctreeStats& stats) {
    octree.info = root;
    octree.info.depth = depth;
    octree.info.max_leaf_splats = params.max_leaf_splats;
    octree.info.node_count = static_cast<std::uint32_t>(octree.nodes.size());
    octree.info.filled_leaves = static_cast<std::uint32_t>(octree.leaf_info.size() - 1);
    octree.info.splat_count = octree.splats.size();
    octree.info.unique_splats = unique;
    octree.info.flags = params.replicate ? pool::k_octree_replicated : 0u;
    stats.nodes = octree.info.node_count;
    stats.depth = depth;
    stats.filled_leaves = octree.info.filled_leaves;
    stats.empty_leaves = static_cast<std::uint32_t>(empty);
    stats.unique_splats = unique;
    stats.stored_splats = octree.splats.size();
    stats.replication_factor = unique == 0 ? 0.0 : double(stats.stored_splats) / double(unique);
    stats.max_leaf_count = max_leaf;
    stats.bytes = octree.nodes.size() * 4 + octree.leaf_info.size() * 4 +
                  octree.splats.size() * sizeof(pool::Splat) + sizeof(pool::OctreeInfo);
}

std::string resolve_octree_backend(const std::string& name, std::string* why) {
#ifdef PRT_HAVE_CUDA
    return choose_backend(
        name, [](std::string* reason) { return cuda::device_available(reason); }, why);
#else
    return choose_backend(name, no_cuda_build, why);
#endif
}

bool octree_uses_point(const pool::Float3& position, const pool::Float3& normal, float radius) {
    double len;
    return usable_build_point(position, normal, radius, len);
}

RootBounds::RootBounds() {
    for (int a = 0; a < 3; ++a) {
        m_lo[a] = std::numeric_limits<double>::infinity();
        m_hi[a] = -std::numeric_limits<double>::infinity();
    }
}

bool RootBounds::add(const pool::Float3& position, const pool::Float3& normal, float radius) {
    double len;
    if (!usable_build_point(position, normal, radius, len)) {
        ++m_skipped;
        return false;
    }
    const double c[3] = {position.x, position.y, position.z};
    for (int a = 0; a < 3; ++a) {
        m_lo[a] = std::min(m_lo[a], c[a] - radius);
        m_hi[a] = std::max(m_hi[a], c[a] + radius);
    }
    ++m_valid;
    return true;
}

void RootBounds::merge(const RootBounds& o) {
    for (int a = 0; a < 3; ++a)
        m_lo[a] = std::min(m_lo[a], o.m_lo[a]), m_hi[a] = std::max(m_hi[a], o.m_hi[a]);
    m_valid += o.m_valid;
    m_skipped += o.m_skipped;
}

pool::OctreeInfo RootBounds::root() const {
    if (m_valid == 0)
        throw Error("octree build: no point has a finite positive radius and a normal (" +
                    std::to_string(m_skipped) + " points)");
    // a cube enclosing every disk (centre +- radius), enlarged by 1/1024
    double extent = 0;
    for (int a = 0; a < 3; ++a) extent = std::max(extent, m_hi[a] - m_lo[a]);
    const double size = extent * (1.0 + 1.0 / 1024.0);
    pool::OctreeInfo info{};
    double root_size = 0;
    for (int a = 0; a < 3; ++a) {
        info.root_min[a] = round_down(0.5 * (m_lo[a] + m_hi[a]) - 0.5 * size);
        root_size = std::max(root_size, m_hi[a] - double(info.root_min[a]));
    }
    info.root_size = round_up(root_size * (1.0 + 1.0 / 4096.0));
    for (int a = 0; a < 3; ++a)
        if (!(double(info.root_min[a]) + double(info.root_size) > m_hi[a]) ||
            !(double(info.root_min[a]) < m_lo[a]))
            throw Error("octree build: the root cube cannot enclose the model in float precision");
    return info;
}

SplatOctree build_octree(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                         std::span<const float> radii, const OctreeParams& params, OctreeStats* stats_out) {
    const double start = tool::now_seconds();
    check_params(params, positions.size());
    const unsigned threads = resolve_threads(params.threads);
    OctreeStats stats;
    RootBounds bounds;
    pre::LargeVector<BuildSplat> splats = build_splats(positions, normals, radii, stats, &bounds, threads);  // thesis 3.1
    const pool::OctreeInfo info = bounds.root();
    sort_by_morton(splats, info, threads);
    SplatOctree octree = build_sorted(std::move(splats), info, NodeCell{}, params, threads, stats);
    stats.seconds = tool::now_seconds() - start;
    if (stats_out) *stats_out = stats;
    return octree;
}

void check_cell_build(const OctreeParams& params, std::size_t points, NodeCell cell) {
    check_params(params, points);
    if (cell.level > params.max_depth)
        throw Error("octree build: cell level " + std::to_string(cell.level) + " exceeds the maximum depth");
}

namespace {

/// build_octree_cell's first steps (thesis 3.1): the usable points' build records, Morton-sorted
/// (stats gets the skipped points), after check_cell_build.
pre::LargeVector<BuildSplat> cell_build_splats(std::span<const pool::Float3> positions,
                                               std::span<const pool::Float3> normals,
                                               std::span<const float> radii, const pool::OctreeInfo& root,
                                               NodeCell cell, const OctreeParams& params,
                                               OctreeStats& stats) {
    check_cell_build(params, positions.size(), cell);
    const unsigned threads = resolve_threads(params.threads);
    pre::LargeVector<BuildSplat> splats = build_splats(positions, normals, radii, stats, nullptr, threads);
    sort_by_morton(splats, root, threads);
    return splats;
}

}  // namespace

SplatOctree build_octree_cell(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                              std::span<const float> radii, const pool::OctreeInfo& root, NodeCell cell,
                              const OctreeParams& params, OctreeStats* stats_out) {
    const double start = tool::now_seconds();
    OctreeStats stats;
    pre::LargeVector<BuildSplat> splats =
        cell_build_splats(positions, normals, radii, root, cell, params, stats);
    SplatOctree octree =
        build_sorted(std::move(splats), root, cell, params, resolve_threads(params.threads), stats);
    stats.seconds = tool::now_seconds() - start;
    if (stats_out) *stats_out = stats;
    return octree;
}

double build_splat_box_bound(double c, float radius) {
    // make_build_splat: e = r sqrt(1 - n_a^2) + 1e-6 r <= r (1 + 1e-6), then c -+ e in double
    // (relative error 2^-53) rounded outward to float (at most one float ulp, <= 2^-23 |c -+ e|):
    // the box lies within c +- (r (1 + 1e-6) + 2^-22 (|c| + 2 r)); 1e-5 and 2^-20 leave room.
    const double r = double(radius);
    return r * (1.0 + 1e-5) + (std::fabs(c) + 2.0 * r) * 0x1p-20;
}

bool prepare_build_splat(const pool::Float3& position, const pool::Float3& normal, float radius,
                         BuildSplat& out) {
    double len;
    if (!usable_build_point(position, normal, radius, len)) return false;
    out = make_build_splat(position, normal, radius, len, 0);
    return true;
}

ChildBoxes child_boxes(const pool::OctreeInfo& root, NodeCell node) {
    ChildBoxes b;
    child_cell_boxes(root, node.level, node.cell, b.mid, b.lo, b.hi);
    return b;
}

std::uint8_t child_overlap_mask(const BuildSplat& splat, const ChildBoxes& boxes, bool replicate) {
    return classify_splat(splat, replicate, boxes.mid, boxes.lo, boxes.hi);
}

void add_octree_sections(SplatOctree octree, pool::PoolWriter& writer) {
    check_octree_limits(octree.nodes.size(), octree.leaf_info.empty() ? 0 : octree.leaf_info.size() - 1,
                        octree.splats.size());
    if (octree.info.node_count != octree.nodes.size() ||
        octree.leaf_info.size() != std::size_t(octree.info.filled_leaves) + 1 ||
        octree.info.splat_count != octree.splats.size())
        throw Error("octree: octree_info counts disagree with the node, leaf and splat arrays");
    writer.add_array(pool::SectionType::octree_info, std::vector<pool::OctreeInfo>{octree.info});
    writer.add_array(pool::SectionType::octree_nodes, std::move(octree.nodes));
    writer.add_array(pool::SectionType::leaf_info, std::move(octree.leaf_info));
    writer.add_array(pool::SectionType::splats, std::move(octree.splats));
}

}  // namespace prt::pre
