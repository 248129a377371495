// PointRT CUDA: the splat octree built level by level on the GPU (thesis 2.2, 3.2, 3.4; the CPU
// builder is preprocess/splat/octree_build.cpp, and this one gives its sections byte for byte).
//
// The CPU builder splits nodes depth first, each node's splat list split into its 8 children's
// lists in list order. Here every node of one level is split at once:
//   1. per node, whether it splits (thesis 3.2: more than X splats, above the maximum depth, the
//      cell-size rule against the mean radius of its list, computed in list order as the CPU does
//      where the node's smallest and largest radius do not decide it);
//   2. per list entry of a splitting node, the children its disk overlaps (core::disk_child_mask,
//      the CPU's function, compiled here without FMA contraction: same doubles, same decisions);
//   3. per child bit, an exclusive scan of the entries with that bit gives each entry its place in
//      the child's list, in list order: the next level's lists are the CPU's.
// The level order of the nodes (parents in order, then children 0..7) is the CPU's breadth-first
// node array; filled leaves are numbered depth first (subtree sizes summed bottom-up, offsets
// handed top-down), and each leaf's splats are written as emit_leaf writes them (centres in the
// leaf's closed box first, then the replicas, each group in list order).
//
// build_cull_octree_cuda (issue 17) goes on on the device: the emit step also writes each filled
// leaf's CullLeaf (node word, level, cell) and the initial keep flags (centre splats first in each
// leaf: exactly cull_build.cpp's centre_flags), the leaves are culled by cull.cu's kernel (thesis
// 3.4, cull_on_stream), and the kept splats are compacted by a scan of the flags, in leaf order
// (cull_build.cpp's cull_octree); only the culled sections come down. It also makes the cell's
// build records itself (thesis 3.1, as the CPU's build_splats then sort_by_morton: the usable points,
// core::make_build_splat in the Morton order of their centres, ties in input order, by a stable radix
// sort), so a cell's points go up as they are and the CPU workers keep their time for the bricks.
#include <cuda_runtime.h>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <vector>

#include "cuda_check.h"
#include "cull_device.h"
#include "device_buffer.h"
#include "prt/core/octree.h"
#include "prt/cuda/octree_cuda.h"

namespace prt::cuda {

namespace {

constexpr unsigned k_block = 256;
constexpr std::uint32_t k_no_node = 0xffffffffu;

struct RootCube {
    float min[3];
    float size;
};

/// A splitting node's children's closed boxes and mid-planes (octree_build.cpp, child_cell_boxes).
struct ChildBoxes {
    double mid[3];
    double lo[8][3];
    double hi[8][3];
};

/// One level's nodes and list entries.
struct Level {
    explicit Level(cudaStream_t s)
        : cell(s),
          begin(s),
          count(s),
          split(s),
          split_rank(s),
          ids(s),
          seg(s),
          sub_leaves(s),
          sub_splats(s),
          leaf_off(s),
          splat_off(s) {}
    std::uint32_t nodes = 0;
    std::uint64_t entries = 0;
    std::uint32_t splits = 0;
    AsyncBuffer<std::uint32_t> cell;        // 3 per node
    AsyncBuffer<std::uint32_t> begin;       // per node: its first entry
    AsyncBuffer<std::uint32_t> count;       // per node: its entries
    AsyncBuffer<std::uint8_t> split;        // per node
    AsyncBuffer<std::uint32_t> split_rank;  // per node: splitting nodes before it
    AsyncBuffer<std::uint32_t> ids;         // per entry: the splat
    AsyncBuffer<std::uint32_t> seg;         // per entry: its node
    AsyncBuffer<unsigned long long> sub_leaves, sub_splats, leaf_off, splat_off;  // per node
};

__device__ inline std::uint64_t thread_index() {
    return std::uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
}

/// pool::make_node in device code (constexpr host functions are not callable there).
__device__ inline std::uint32_t node_word(pool::NodeType type, std::uint64_t address) {
    return (static_cast<std::uint32_t>(type) << pool::k_node_address_bits) |
           (static_cast<std::uint32_t>(address) & pool::k_node_address_max);
}

/// Per node: the smallest and largest radius of its list (float bits: radii are positive), and the
/// centres in its half-open cell (split_by_centres). A warp whose entries share one node adds once.
__global__ void node_stats_kernel(std::uint64_t entries, const std::uint32_t* ids, const std::uint32_t* seg,
                                  const core::BuildSplat* splats, unsigned* rmin, unsigned* rmax,
                                  unsigned* centres, RootCube root, std::uint32_t level,
                                  const std::uint32_t* cells, bool need_centres) {
    const std::uint64_t k = thread_index();
    const bool active = k < entries;
    const std::uint32_t n = active ? seg[k] : k_no_node;
    unsigned bits_lo = 0xffffffffu, bits_hi = 0u, inside = 0u;
    if (active) {
        const core::BuildSplat& s = splats[ids[k]];
        bits_lo = bits_hi = __float_as_uint(s.r);
        if (need_centres) {
            double lo[3], hi[3];
            core::octree_node_box(root.min, root.size, level, cells + 3 * std::size_t(n), lo, hi);
            bool in = true;
            for (int a = 0; a < 3; ++a) in = in && double(s.c[a]) >= lo[a] && double(s.c[a]) < hi[a];
            inside = in ? 1u : 0u;
        }
    }
    const unsigned full = 0xffffffffu;
    const std::uint32_t n0 = __shfl_sync(full, n, 0);
    if (__all_sync(full, n == n0 || n == k_no_node)) {
        const unsigned lo = __reduce_min_sync(full, bits_lo), hi = __reduce_max_sync(full, bits_hi);
        const unsigned c = __reduce_add_sync(full, inside);
        if ((threadIdx.x & 31u) == 0 && n0 != k_no_node) {
            atomicMin(&rmin[n0], lo);
            atomicMax(&rmax[n0], hi);
            if (c) atomicAdd(&centres[n0], c);
        }
    } else if (active) {
        atomicMin(&rmin[n], bits_lo);
        atomicMax(&rmax[n], bits_hi);
        if (inside) atomicAdd(&centres[n], 1u);
    }
}

/// Per node: whether it splits (octree_build.cpp, should_split and octree_splits_node).
__global__ void decide_kernel(std::uint32_t nodes, const std::uint32_t* counts, const std::uint32_t* begin,
                              const unsigned* rmin, const unsigned* rmax, const unsigned* centres,
                              const std::uint32_t* ids, const core::BuildSplat* splats, OctreeCudaParams p,
                              RootCube root, std::uint32_t level, std::uint8_t* split) {
    const std::uint64_t i = thread_index();
    if (i >= nodes) return;
    const std::uint32_t count = counts[i];
    bool s = true;
    if (count <= p.max_leaf_splats || level >= p.max_depth) {
        s = false;
    } else if (p.split_by_centres && p.replicate && centres[i] <= p.max_leaf_splats) {
        s = false;
    } else if (p.min_cell_ratio > 0) {
        // The CPU: no split when edge < ratio x (sum of the list's radii in list order / count).
        // That mean lies within 5e-7 (relative) of [smallest, largest radius] for any list of
        // fewer than 2^32 entries, so outside a band of 1e-6 the bounds decide alone.
        const double edge = double(root.size) / double(std::uint64_t(1) << level);
        const double ratio = double(p.min_cell_ratio);
        const double lo = double(__uint_as_float(rmin[i])), hi = double(__uint_as_float(rmax[i]));
        if (edge < ratio * lo * (1.0 - 1e-6)) {
            s = false;
        } else if (!(edge >= ratio * hi * (1.0 + 1e-6))) {
            double sum = 0;
            const std::uint32_t b = begin[i];
            for (std::uint32_t k = 0; k < count; ++k) sum += splats[ids[b + k]].r;
            s = !(edge < ratio * (sum / double(count)));
        }
    }
    split[i] = s ? 1 : 0;
}

/// Per splitting node: its children's boxes (child_cell_boxes), its children's cells.
__global__ void children_kernel(std::uint32_t nodes, const std::uint8_t* split,
                                const std::uint32_t* split_rank, const std::uint32_t* cells, RootCube root,
                                std::uint32_t level, ChildBoxes* boxes, std::uint32_t* next_cells) {
    const std::uint64_t i = thread_index();
    if (i >= nodes || !split[i]) return;
    const std::uint32_t s = split_rank[i];
    ChildBoxes& b = boxes[s];
    for (unsigned child = 0; child < 8; ++child) {
        const std::uint32_t cc[3] = {2 * cells[3 * i] + (child & 1u),
                                     2 * cells[3 * i + 1] + (child >> 1 & 1u),
                                     2 * cells[3 * i + 2] + (child >> 2 & 1u)};
        core::octree_node_box(root.min, root.size, level + 1, cc, b.lo[child], b.hi[child]);
        for (int a = 0; a < 3; ++a) next_cells[3 * (8 * std::size_t(s) + child) + a] = cc[a];
    }
    for (int a = 0; a < 3; ++a) b.mid[a] = b.hi[0][a];
}

/// Per entry of a splitting node: the children its disk belongs to; counts per child.
__global__ void classify_kernel(std::uint64_t entries, const std::uint32_t* ids, const std::uint32_t* seg,
                                const std::uint8_t* split, const std::uint32_t* split_rank,
                                const ChildBoxes* boxes, const core::BuildSplat* splats, bool replicate,
                                std::uint8_t* masks, unsigned* child_count) {
    const std::uint64_t k = thread_index();
    const bool active = k < entries;
    std::uint32_t n = k_no_node, s = 0;
    unsigned m = 0;
    if (active) {
        n = seg[k];
        if (split[n]) {
            s = split_rank[n];
            const ChildBoxes& b = boxes[s];
            m = core::disk_child_mask(splats[ids[k]], replicate, b.mid, b.lo, b.hi);
        } else {
            n = k_no_node;  // a leaf's entries are not split
        }
        masks[k] = static_cast<std::uint8_t>(m);
    }
    const unsigned full = 0xffffffffu;
    const std::uint32_t n0 = __shfl_sync(full, n, 0);
    if (__all_sync(full, n == n0)) {
        if (n0 == k_no_node) return;
        for (unsigned c = 0; c < 8; ++c) {
            const unsigned cnt = __popc(__ballot_sync(full, (m >> c) & 1u));
            if ((threadIdx.x & 31u) == 0 && cnt) atomicAdd(&child_count[8 * std::size_t(s) + c], cnt);
        }
    } else if (n != k_no_node) {
        for (unsigned c = 0; c < 8; ++c)
            if ((m >> c) & 1u) atomicAdd(&child_count[8 * std::size_t(s) + c], 1u);
    }
}

__global__ void iota_kernel(std::uint64_t count, std::uint32_t* out) {
    const std::uint64_t k = thread_index();
    if (k < count) out[k] = static_cast<std::uint32_t>(k);
}

__global__ void bit_flags_kernel(std::uint64_t entries, const std::uint8_t* masks, unsigned bit,
                                 std::uint32_t* flags) {
    const std::uint64_t k = thread_index();
    if (k < entries) flags[k] = (masks[k] >> bit) & 1u;
}

/// Entries with child bit `bit` to their place in that child's list (list order kept).
__global__ void scatter_kernel(std::uint64_t entries, const std::uint8_t* masks, unsigned bit,
                               const std::uint32_t* rank, const std::uint32_t* ids, const std::uint32_t* seg,
                               const std::uint32_t* begin, const std::uint32_t* split_rank,
                               const std::uint32_t* next_begin, std::uint32_t* next_ids,
                               std::uint32_t* next_seg) {
    const std::uint64_t k = thread_index();
    if (k >= entries || !((masks[k] >> bit) & 1u)) return;
    const std::uint32_t n = seg[k];
    const std::uint32_t j = 8 * split_rank[n] + bit;
    const std::uint32_t pos = next_begin[j] + (rank[k] - rank[begin[n]]);
    next_ids[pos] = ids[k];
    next_seg[pos] = j;
}

/// Bottom-up: filled leaves and stored splats in each node's subtree.
__global__ void subtree_kernel(std::uint32_t nodes, const std::uint8_t* split,
                               const std::uint32_t* split_rank, const std::uint32_t* counts,
                               const unsigned long long* child_leaves, const unsigned long long* child_splats,
                               unsigned long long* leaves, unsigned long long* stored) {
    const std::uint64_t i = thread_index();
    if (i >= nodes) return;
    if (split[i]) {
        unsigned long long l = 0, s = 0;
        const std::size_t first = 8 * std::size_t(split_rank[i]);
        for (unsigned c = 0; c < 8; ++c) {
            l += child_leaves[first + c];
            s += child_splats[first + c];
        }
        leaves[i] = l;
        stored[i] = s;
    } else {
        leaves[i] = counts[i] > 0 ? 1 : 0;
        stored[i] = counts[i];
    }
}

/// Top-down: each child's first leaf and first stored splat (depth-first order).
__global__ void offsets_kernel(std::uint32_t nodes, const std::uint8_t* split,
                               const std::uint32_t* split_rank, const unsigned long long* leaf_off,
                               const unsigned long long* splat_off, const unsigned long long* child_leaves,
                               const unsigned long long* child_splats, unsigned long long* child_leaf_off,
                               unsigned long long* child_splat_off) {
    const std::uint64_t i = thread_index();
    if (i >= nodes || !split[i]) return;
    unsigned long long l = leaf_off[i], s = splat_off[i];
    const std::size_t first = 8 * std::size_t(split_rank[i]);
    for (unsigned c = 0; c < 8; ++c) {
        child_leaf_off[first + c] = l;
        child_splat_off[first + c] = s;
        l += child_leaves[first + c];
        s += child_splats[first + c];
    }
}

/// One level's node words, and its filled leaves' ranges and splats (octree_build.cpp, emit_leaf).
__global__ void emit_kernel(std::uint32_t nodes, const std::uint8_t* split, const std::uint32_t* split_rank,
                            const std::uint32_t* counts, const std::uint32_t* begin, const std::uint32_t* ids,
                            const std::uint32_t* cells, const unsigned long long* leaf_off,
                            const unsigned long long* splat_off, std::uint64_t next_level_start,
                            RootCube root, std::uint32_t level, const core::BuildSplat* splats,
                            std::uint32_t* out_nodes, std::uint32_t* leaf_info, pool::Splat* out_splats,
                            unsigned long long* empty, unsigned long long* max_leaf,
                            core::CullLeaf* cull_leaves, std::uint8_t* keep) {
    const std::uint64_t i = thread_index();
    if (i >= nodes) return;
    const std::uint32_t count = counts[i];
    if (split[i]) {
        out_nodes[i] =
            node_word(pool::NodeType::internal, next_level_start + 8 * std::uint64_t(split_rank[i]));
        return;
    }
    if (count == 0) {
        out_nodes[i] = node_word(pool::NodeType::empty_leaf, 0);
        atomicAdd(empty, 1ull);
        return;
    }
    const unsigned long long leaf = leaf_off[i];
    const std::uint32_t word = node_word(pool::NodeType::filled_leaf, leaf);
    out_nodes[i] = word;
    if (cull_leaves)
        cull_leaves[leaf] = core::CullLeaf{word, level, {cells[3 * i], cells[3 * i + 1], cells[3 * i + 2]}};
    atomicMax(max_leaf, static_cast<unsigned long long>(count));
    std::uint64_t o = splat_off[i];
    leaf_info[leaf] = static_cast<std::uint32_t>(o);
    double lo[3], hi[3];
    core::octree_node_box(root.min, root.size, level, cells + 3 * i, lo, hi);
    const std::uint32_t b = begin[i];
    for (int pass = 0; pass < 2; ++pass) {
        for (std::uint32_t k = 0; k < count; ++k) {
            const core::BuildSplat& s = splats[ids[b + k]];
            bool inside = true;
            for (int a = 0; a < 3; ++a)
                if (!(double(s.c[a]) >= lo[a] && double(s.c[a]) <= hi[a])) inside = false;
            if (inside != (pass == 0)) continue;
            if (keep) keep[o] = pass == 0 ? core::k_keep_centre : core::k_keep_none;
            pool::Splat& out = out_splats[o++];
            out.position = pool::Float3{s.c[0], s.c[1], s.c[2]};
            out.radius = s.r;
            out.normal = pool::Float3{s.n[0], s.n[1], s.n[2]};
            out.point = s.point;
        }
    }
}

/// Culling's compaction (cull_build.cpp, cull_octree): 1 per kept splat.
__global__ void kept_flags_kernel(std::uint64_t count, const std::uint8_t* keep, std::uint32_t* flags) {
    const std::uint64_t k = thread_index();
    if (k < count) flags[k] = keep[k] != core::k_keep_none ? 1u : 0u;
}

/// Each filled leaf's first kept splat: the kept splats before its first stored one.
__global__ void culled_leaf_info_kernel(std::uint32_t filled, const std::uint32_t* leaf_info,
                                        const std::uint32_t* kept_before, std::uint32_t* out) {
    const std::uint64_t a = thread_index();
    if (a < filled) out[a] = kept_before[leaf_info[a]];
}

__global__ void compact_kernel(std::uint64_t count, const std::uint8_t* keep,
                               const std::uint32_t* kept_before, const pool::Splat* in, pool::Splat* out) {
    const std::uint64_t k = thread_index();
    if (k < count && keep[k] != core::k_keep_none) out[kept_before[k]] = in[k];
}

/// Exclusive prefix sums of `count` uint32 on `stream` (cub), `temp` grown as needed.
void exclusive_sum(const std::uint32_t* in, std::uint32_t* out, std::uint64_t count,
                   AsyncBuffer<std::uint8_t>& temp, cudaStream_t stream) {
    if (count == 0) return;
    std::size_t bytes = 0;
    PRT_CUDA_CHECK(
        cub::DeviceScan::ExclusiveSum(nullptr, bytes, in, out, static_cast<std::int64_t>(count), stream));
    temp.reserve(bytes);
    PRT_CUDA_CHECK(
        cub::DeviceScan::ExclusiveSum(temp.data(), bytes, in, out, static_cast<std::int64_t>(count), stream));
}

template <class T>
T read_back(const T* device, cudaStream_t stream) {
    T v{};
    PRT_CUDA_CHECK(cudaMemcpyAsync(&v, device, sizeof(T), cudaMemcpyDeviceToHost, stream));
    PRT_CUDA_CHECK(cudaStreamSynchronize(stream));
    return v;
}

// ---- A cell's build records (thesis 3.1) ----------------------------------------------------------

/// The key of a point the builder skips: after every usable point's (a Morton code of 63 bits).
constexpr std::uint64_t k_unusable_key = ~std::uint64_t{0};

/// Per point: its Morton key (core::build_splat_morton_key, or k_unusable_key) and its index; `usable`
/// counts the usable points (a warp's count added by its first lane).
__global__ void point_keys_kernel(std::uint64_t n, const pool::Float3* __restrict__ positions,
                                  const pool::Float3* __restrict__ normals, const float* __restrict__ radii,
                                  RootCube root, double scale, std::uint64_t* __restrict__ keys,
                                  std::uint32_t* __restrict__ index, unsigned long long* usable) {
    const std::uint64_t i = thread_index();
    bool ok = false;
    if (i < n) {
        const pool::Float3 p = positions[i];
        double len;
        ok = core::usable_build_point(p, normals[i], radii[i], len);
        const float c[3] = {p.x, p.y, p.z};
        keys[i] = ok ? core::build_splat_morton_key(c, root.min, scale) : k_unusable_key;
        index[i] = static_cast<std::uint32_t>(i);
    }
    const unsigned ballot = __ballot_sync(0xffffffffu, ok);  // the grid is whole warps (k_block)
    if ((threadIdx.x & 31u) == 0u && ballot != 0u)
        atomicAdd(usable, static_cast<unsigned long long>(__popc(ballot)));
}

/// The build records in sorted order: record j is point order[j]'s (core::make_build_splat).
__global__ void build_splats_kernel(std::uint64_t count, const std::uint32_t* __restrict__ order,
                                    const pool::Float3* __restrict__ positions,
                                    const pool::Float3* __restrict__ normals, const float* __restrict__ radii,
                                    core::BuildSplat* __restrict__ out) {
    const std::uint64_t j = thread_index();
    if (j >= count) return;
    const std::uint32_t i = order[j];
    double len;
    core::usable_build_point(positions[i], normals[i], radii[i], len);
    out[j] = core::make_build_splat(positions[i], normals[i], radii[i], len, i);
}

/// thesis 3.1 on the device: the usable points of `points` as build records in the CPU builder's
/// order (build_splats, then sort_by_morton: Morton order of the centres in the root cube, ties in
/// input order; the radix sort of (key, index) pairs made in index order is stable) into `out`.
/// Returns how many.
std::uint64_t device_build_splats(const CellPoints& points, const RootCube& root, cudaStream_t st,
                                  AsyncBuffer<core::BuildSplat>& out) {
    const std::uint64_t n = points.positions.size();
    if (points.normals.size() != n || points.radii.size() != n)
        throw Error("build_cull_octree_cuda: " + std::to_string(n) + " positions but " +
                    std::to_string(points.normals.size()) + " normals and " +
                    std::to_string(points.radii.size()) + " radii");
    if (n == 0) return 0;
    AsyncBuffer<pool::Float3> positions(st), normals(st);
    AsyncBuffer<float> radii(st);
    positions.upload(points.positions.data(), n);
    normals.upload(points.normals.data(), n);
    radii.upload(points.radii.data(), n);
    AsyncBuffer<std::uint64_t> keys(st), sorted_keys(st);
    AsyncBuffer<std::uint32_t> index(st), order(st);
    AsyncBuffer<unsigned long long> usable(st);
    keys.resize(n);
    sorted_keys.resize(n);
    index.resize(n);
    order.resize(n);
    usable.resize(1);
    PRT_CUDA_CHECK(cudaMemsetAsync(usable.data(), 0, usable.bytes(), st));
    const double scale = core::build_splat_morton_scale(root.size);
    launch_kernel(launch_1d(n, k_block, st), point_keys_kernel, n, positions.data(), normals.data(),
                  radii.data(), root, scale, keys.data(), index.data(), usable.data());
    AsyncBuffer<std::uint8_t> temp(st);
    std::size_t bytes = 0;
    const auto items = static_cast<std::int64_t>(n);
    PRT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys.data(), sorted_keys.data(),
                                                   index.data(), order.data(), items, 0, 64, st));
    temp.reserve(bytes);
    PRT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp.data(), bytes, keys.data(), sorted_keys.data(),
                                                   index.data(), order.data(), items, 0, 64, st));
    const std::uint64_t count = read_back(usable.data(), st);
    out.resize(count);
    if (count)
        launch_kernel(launch_1d(count, k_block, st), build_splats_kernel, count, order.data(),
                      positions.data(), normals.data(), radii.data(), out.data());
    return count;
}

/// A subtree built on the device (build_levels), its sections still there.
struct DeviceTree {
    explicit DeviceTree(cudaStream_t s) : nodes(s), leaf_info(s), splats(s), leaves(s), keep(s) {}
    std::uint64_t node_count = 0, filled = 0, stored = 0;
    std::uint32_t depth = 0;  ///< the deepest leaf's level in the whole octree's numbering
    unsigned long long empty_leaves = 0, max_leaf = 0;
    AsyncBuffer<std::uint32_t> nodes, leaf_info;  // leaf_info: filled + 1
    AsyncBuffer<pool::Splat> splats;
    AsyncBuffer<core::CullLeaf> leaves;  // for culling only: per filled leaf
    AsyncBuffer<std::uint8_t> keep;      // for culling only: per stored splat, centre_flags' flags
};

/// The subtree below (level0, cell) over the Morton-sorted build records `d_splats` (`count`, device
/// memory) built level by level on `st`; with `for_culling`, t.leaves and t.keep are filled too.
void build_levels(const core::BuildSplat* d_splats, std::uint64_t count, const RootCube& root,
                  std::uint32_t level0, const std::uint32_t cell[3], const OctreeCudaParams& params,
                  const std::function<void(std::uint64_t, std::uint64_t, std::uint64_t)>& check,
                  bool for_culling, cudaStream_t st, DeviceTree& t) {
    AsyncBuffer<std::uint8_t> temp(st), masks(st);
    AsyncBuffer<std::uint32_t> flags(st), rank(st);
    AsyncBuffer<unsigned> rmin(st), rmax(st), centres(st);
    AsyncBuffer<ChildBoxes> boxes(st);

    // The start node and its list: every splat, in the given order.
    std::vector<Level> levels;
    levels.emplace_back(st);
    {
        Level& l = levels[0];
        l.nodes = 1;
        l.entries = count;
        const std::uint32_t start[5] = {cell[0], cell[1], cell[2], 0, static_cast<std::uint32_t>(count)};
        l.cell.upload(start, 3);
        l.begin.upload(start + 3, 1);
        l.count.upload(start + 4, 1);
        l.ids.resize(l.entries);
        launch_kernel(launch_1d(l.entries, k_block, st), iota_kernel, l.entries, l.ids.data());
        l.seg.resize(l.entries);
        PRT_CUDA_CHECK(cudaMemsetAsync(l.seg.data(), 0, l.seg.bytes(), st));
        PRT_CUDA_CHECK(cudaStreamSynchronize(st));  // `start` goes out of scope
    }
    std::uint64_t total_nodes = 1;
    for (std::uint32_t depth = 0;; ++depth) {
        Level& l = levels[depth];
        const std::uint32_t lev = level0 + depth;
        // 1. splits
        rmin.reserve(l.nodes);
        rmax.reserve(l.nodes);
        centres.reserve(l.nodes);
        PRT_CUDA_CHECK(cudaMemsetAsync(rmin.data(), 0xff, l.nodes * sizeof(unsigned), st));
        PRT_CUDA_CHECK(cudaMemsetAsync(rmax.data(), 0, l.nodes * sizeof(unsigned), st));
        PRT_CUDA_CHECK(cudaMemsetAsync(centres.data(), 0, l.nodes * sizeof(unsigned), st));
        const bool need_centres = params.split_by_centres && params.replicate;
        if (l.entries)
            launch_kernel(launch_1d(l.entries, k_block, st), node_stats_kernel, l.entries, l.ids.data(),
                          l.seg.data(), d_splats, rmin.data(), rmax.data(), centres.data(), root, lev,
                          l.cell.data(), need_centres);
        l.split.resize(l.nodes);
        l.split_rank.resize(l.nodes);
        launch_kernel(launch_1d(l.nodes, k_block, st), decide_kernel, l.nodes, l.count.data(), l.begin.data(),
                      rmin.data(), rmax.data(), centres.data(), l.ids.data(), d_splats, params, root, lev,
                      l.split.data());
        flags.reserve(l.nodes);
        launch_kernel(launch_1d(l.nodes, k_block, st), bit_flags_kernel, std::uint64_t(l.nodes),
                      l.split.data(), 0u, flags.data());
        exclusive_sum(flags.data(), l.split_rank.data(), l.nodes, temp, st);
        const std::uint32_t last_rank = read_back(l.split_rank.data() + (l.nodes - 1), st);
        const std::uint8_t last_split = read_back(l.split.data() + (l.nodes - 1), st);
        l.splits = last_rank + last_split;
        if (l.splits == 0) break;
        // 2. children: boxes, cells, each entry's child mask and the children's counts
        Level next(st);
        next.nodes = 8 * l.splits;
        total_nodes += next.nodes;
        check(total_nodes, 0, 0);
        boxes.reserve(l.splits);
        next.cell.resize(3 * std::size_t(next.nodes));
        launch_kernel(launch_1d(l.nodes, k_block, st), children_kernel, l.nodes, l.split.data(),
                      l.split_rank.data(), l.cell.data(), root, lev, boxes.data(), next.cell.data());
        next.count.resize(next.nodes);
        PRT_CUDA_CHECK(cudaMemsetAsync(next.count.data(), 0, next.count.bytes(), st));
        masks.reserve(l.entries);
        launch_kernel(launch_1d(l.entries, k_block, st), classify_kernel, l.entries, l.ids.data(),
                      l.seg.data(), l.split.data(), l.split_rank.data(), boxes.data(), d_splats,
                      params.replicate, masks.data(), next.count.data());
        next.begin.resize(next.nodes);
        exclusive_sum(next.count.data(), next.begin.data(), next.nodes, temp, st);
        next.entries = std::uint64_t(read_back(next.begin.data() + (next.nodes - 1), st)) +
                       read_back(next.count.data() + (next.nodes - 1), st);
        check(0, 0, next.entries);  // positions are 32-bit: refused before they could wrap
        // 3. the children's lists, one child bit at a time
        next.ids.resize(next.entries);
        next.seg.resize(next.entries);
        flags.reserve(l.entries);
        rank.reserve(l.entries);
        for (unsigned bit = 0; bit < 8; ++bit) {
            launch_kernel(launch_1d(l.entries, k_block, st), bit_flags_kernel, l.entries, masks.data(), bit,
                          flags.data());
            exclusive_sum(flags.data(), rank.data(), l.entries, temp, st);
            launch_kernel(launch_1d(l.entries, k_block, st), scatter_kernel, l.entries, masks.data(), bit,
                          rank.data(), l.ids.data(), l.seg.data(), l.begin.data(), l.split_rank.data(),
                          next.begin.data(), next.ids.data(), next.seg.data());
        }
        l.seg.release();  // kept: cells, counts, begins and ids (leaves)
        levels.push_back(std::move(next));
    }
    masks.release();
    flags.release();
    rank.release();
    boxes.release();

    // Depth-first numbering: subtree sizes bottom-up, offsets top-down.
    const std::size_t depth_count = levels.size();
    for (Level& l : levels) {
        l.sub_leaves.resize(l.nodes);
        l.sub_splats.resize(l.nodes);
        l.leaf_off.resize(l.nodes);
        l.splat_off.resize(l.nodes);
    }
    for (std::size_t d = depth_count; d-- > 0;) {
        Level& l = levels[d];
        const Level* child = d + 1 < depth_count ? &levels[d + 1] : nullptr;
        launch_kernel(launch_1d(l.nodes, k_block, st), subtree_kernel, l.nodes, l.split.data(),
                      l.split_rank.data(), l.count.data(), child ? child->sub_leaves.data() : nullptr,
                      child ? child->sub_splats.data() : nullptr, l.sub_leaves.data(), l.sub_splats.data());
    }
    PRT_CUDA_CHECK(cudaMemsetAsync(levels[0].leaf_off.data(), 0, sizeof(unsigned long long), st));
    PRT_CUDA_CHECK(cudaMemsetAsync(levels[0].splat_off.data(), 0, sizeof(unsigned long long), st));
    for (std::size_t d = 0; d + 1 < depth_count; ++d) {
        Level& l = levels[d];
        Level& c = levels[d + 1];
        launch_kernel(launch_1d(l.nodes, k_block, st), offsets_kernel, l.nodes, l.split.data(),
                      l.split_rank.data(), l.leaf_off.data(), l.splat_off.data(), c.sub_leaves.data(),
                      c.sub_splats.data(), c.leaf_off.data(), c.splat_off.data());
    }
    const unsigned long long filled = read_back(levels[0].sub_leaves.data(), st);
    const unsigned long long stored = read_back(levels[0].sub_splats.data(), st);
    check(total_nodes, filled, stored);

    t.node_count = total_nodes;
    t.filled = filled;
    t.stored = stored;
    t.depth = static_cast<std::uint32_t>(level0 + depth_count - 1);
    t.nodes.resize(total_nodes);
    t.leaf_info.resize(filled + 1);
    t.splats.resize(stored);
    if (for_culling) {
        t.leaves.resize(filled);
        t.keep.resize(stored);
    }
    AsyncBuffer<unsigned long long> d_stats(st);  // empty leaves, largest leaf
    d_stats.resize(2);
    PRT_CUDA_CHECK(cudaMemsetAsync(d_stats.data(), 0, d_stats.bytes(), st));
    std::uint64_t level_start = 0;
    for (std::size_t d = 0; d < depth_count; ++d) {
        Level& l = levels[d];
        launch_kernel(launch_1d(l.nodes, k_block, st), emit_kernel, l.nodes, l.split.data(),
                      l.split_rank.data(), l.count.data(), l.begin.data(), l.ids.data(), l.cell.data(),
                      l.leaf_off.data(), l.splat_off.data(), level_start + l.nodes, root,
                      static_cast<std::uint32_t>(level0 + d), d_splats, t.nodes.data() + level_start,
                      t.leaf_info.data(), t.splats.data(), d_stats.data(), d_stats.data() + 1,
                      for_culling ? t.leaves.data() : nullptr, for_culling ? t.keep.data() : nullptr);
        level_start += l.nodes;
    }
    const std::uint32_t end = static_cast<std::uint32_t>(stored);
    PRT_CUDA_CHECK(
        cudaMemcpyAsync(t.leaf_info.data() + filled, &end, sizeof end, cudaMemcpyHostToDevice, st));
    unsigned long long stats[2];
    PRT_CUDA_CHECK(cudaMemcpyAsync(stats, d_stats.data(), sizeof stats, cudaMemcpyDeviceToHost, st));
    PRT_CUDA_CHECK(cudaStreamSynchronize(st));  // `end` and `stats` are on this stack
    t.empty_leaves = stats[0];
    t.max_leaf = stats[1];
}

/// build_levels over host records: `check`ed, uploaded, built; the records freed again.
void build_tree(std::span<const core::BuildSplat> splats, const float root_min[3], float root_size,
                std::uint32_t level0, const std::uint32_t cell[3], const OctreeCudaParams& params,
                const std::function<void(std::uint64_t, std::uint64_t, std::uint64_t)>& check,
                bool for_culling, cudaStream_t st, DeviceTree& t) {
    check(1, 0, splats.size());
    AsyncBuffer<core::BuildSplat> d_splats(st);
    d_splats.upload(splats.data(), splats.size());
    const RootCube root{{root_min[0], root_min[1], root_min[2]}, root_size};
    build_levels(d_splats.data(), splats.size(), root, level0, cell, params, check, for_culling, st, t);
}

}  // namespace

void build_octree_cuda(std::span<const core::BuildSplat> splats, const float root_min[3], float root_size,
                       std::uint32_t level0, const std::uint32_t cell[3], const OctreeCudaParams& params,
                       const std::function<void(std::uint64_t, std::uint64_t, std::uint64_t)>& check,
                       OctreeCudaResult& out) {
    PRT_CUDA_CHECK(cudaSetDevice(0));
    keep_pool_memory();
    OwnedStream stream;
    const cudaStream_t st = stream.get();
    DeviceTree t(st);
    build_tree(splats, root_min, root_size, level0, cell, params, check, false, st, t);
    out.nodes.resize(t.node_count);
    out.leaf_info.resize(t.filled + 1);
    out.splats.resize(t.stored);
    t.nodes.download(out.nodes.data(), t.node_count);
    t.leaf_info.download(out.leaf_info.data(), t.filled + 1);
    t.splats.download(out.splats.data(), t.stored);
    PRT_CUDA_CHECK(cudaStreamSynchronize(st));
    out.depth = t.depth;
    out.empty_leaves = t.empty_leaves;
    out.max_leaf = t.max_leaf;
    out.stored = t.stored;
}

void build_cull_octree_cuda(const CellPoints& points, const float root_min[3], float root_size,
                            std::uint32_t level0, const std::uint32_t cell[3], const OctreeCudaParams& params,
                            const core::CullView& probes,
                            const std::function<void(std::uint64_t, std::uint64_t, std::uint64_t)>& check,
                            OctreeCudaResult& out, core::CullCounters* counters) {
    if (!params.replicate) throw Error("build_cull_octree_cuda: culling needs a replicated octree");
    PRT_CUDA_CHECK(cudaSetDevice(0));
    keep_pool_memory();
    OwnedStream stream;
    const cudaStream_t st = stream.get();
    DeviceTree t(st);
    const RootCube root{{root_min[0], root_min[1], root_min[2]}, root_size};
    {
        AsyncBuffer<core::BuildSplat> splats(st);
        out.usable = device_build_splats(points, root, st, splats);
        if (out.usable == 0)  // as the CPU's build_splats
            throw Error("octree build: no point has a finite positive radius and a normal (" +
                        std::to_string(points.positions.size()) + " points)");
        check(1, 0, out.usable);
        build_levels(splats.data(), out.usable, root, level0, cell, params, check, true, st, t);
    }

    // Culling (thesis 3.4) over the tree as the CPU path sees it (cull_build.cpp, octree_view).
    pool::OctreeInfo info{};
    for (int a = 0; a < 3; ++a) info.root_min[a] = root_min[a];
    info.root_size = root_size;
    info.depth = t.depth;
    info.max_leaf_splats = params.max_leaf_splats;
    info.node_count = static_cast<std::uint32_t>(t.node_count);
    info.filled_leaves = static_cast<std::uint32_t>(t.filled);
    info.splat_count = t.stored;
    info.unique_splats = out.usable;
    info.flags = pool::k_octree_replicated;
    AsyncBuffer<core::ProbeDirection> d_dirs(st);
    d_dirs.upload(probes.directions, std::size_t(probes.direction_sets) * probes.directions_per_set);
    AsyncBuffer<std::uint32_t> d_votes(st);
    if (probes.policy == core::CullPolicy::votes && t.stored) {
        d_votes.resize(t.stored);
        PRT_CUDA_CHECK(cudaMemsetAsync(d_votes.data(), 0, d_votes.bytes(), st));
    }
    core::CullView view = probes;
    view.octree = core::make_octree_view(info, t.nodes.data(), t.leaf_info.data(), t.splats.data());
    view.leaves = t.leaves.data();
    view.directions = d_dirs.data();
    const core::CullCounters c = cull_on_stream(view, t.keep.data(), d_votes.data(), st, {});
    if (counters) *counters = c;
    d_votes.release();
    t.leaves.release();

    // The kept splats in their leaf order, and the leaves' new ranges (cull_octree).
    AsyncBuffer<std::uint32_t> flags(st), kept_before(st), culled_info(st);
    AsyncBuffer<std::uint8_t> temp(st);
    std::uint64_t kept = 0;
    if (t.stored) {
        flags.resize(t.stored);
        kept_before.resize(t.stored);
        launch_kernel(launch_1d(t.stored, k_block, st), kept_flags_kernel, t.stored, t.keep.data(),
                      flags.data());
        exclusive_sum(flags.data(), kept_before.data(), t.stored, temp, st);
        kept = std::uint64_t(read_back(kept_before.data() + (t.stored - 1), st)) +
               read_back(flags.data() + (t.stored - 1), st);
        flags.release();
    }
    culled_info.resize(t.filled + 1);
    if (t.filled)
        launch_kernel(launch_1d(t.filled, k_block, st), culled_leaf_info_kernel,
                      static_cast<std::uint32_t>(t.filled), t.leaf_info.data(), kept_before.data(),
                      culled_info.data());
    const std::uint32_t end = static_cast<std::uint32_t>(kept);
    PRT_CUDA_CHECK(
        cudaMemcpyAsync(culled_info.data() + t.filled, &end, sizeof end, cudaMemcpyHostToDevice, st));
    AsyncBuffer<pool::Splat> culled(st);
    culled.resize(kept);
    if (kept)
        launch_kernel(launch_1d(t.stored, k_block, st), compact_kernel, t.stored, t.keep.data(),
                      kept_before.data(), t.splats.data(), culled.data());
    out.nodes.resize(t.node_count);
    out.leaf_info.resize(t.filled + 1);
    out.splats.resize(kept);
    t.nodes.download(out.nodes.data(), t.node_count);
    culled_info.download(out.leaf_info.data(), t.filled + 1);
    culled.download(out.splats.data(), kept);
    PRT_CUDA_CHECK(cudaStreamSynchronize(st));  // `end` is on this stack
    out.depth = t.depth;
    out.empty_leaves = t.empty_leaves;
    out.max_leaf = t.max_leaf;
    out.stored = t.stored;
}

}  // namespace prt::cuda
