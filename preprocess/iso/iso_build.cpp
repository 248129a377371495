// PointRT: the Implicit Surface Octree builder (thesis ch. 4). See iso_build.h for the steps.
#include "iso_build.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <numbers>
#include <numeric>
#include <span>
#include <string>

#include "buffer.h"
#include "disk_box.h"
#include "iso_morton.h"
#include "kd_tree.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "radix_sort.h"

namespace prt::iso {

using detail::Frame;
using detail::k_code_level;
using pre::morton3;

const char* radius_source_name(RadiusSource s) {
    switch (s) {
        case RadiusSource::automatic:
            return "auto";
        case RadiusSource::radii:
            return "radii";
        case RadiusSource::knn:
            return "knn";
    }
    return "?";
}

RadiusSource parse_radius_source(const std::string& name) {
    if (name == "auto") return RadiusSource::automatic;
    if (name == "radii") return RadiusSource::radii;
    if (name == "knn") return RadiusSource::knn;
    throw Error("unknown radius source '" + name + "' (auto, radii or knn)");
}

const char* storage_name(Storage s) {
    switch (s) {
        case Storage::q8:
            return "q8";
        case Storage::f32:
            return "f32";
        case Storage::both:
            return "both";
    }
    return "?";
}

Storage parse_storage(const std::string& name) {
    if (name == "q8") return Storage::q8;
    if (name == "f32") return Storage::f32;
    if (name == "both") return Storage::both;
    throw Error("unknown storage '" + name + "' (q8, f32 or both)");
}

void validate(const BuildOptions& o) {
    if (o.max_level > pool::k_max_iso_level)
        throw Error("max level " + std::to_string(o.max_level) + " exceeds " +
                    std::to_string(pool::k_max_iso_level));
    if (o.min_level > o.max_level)
        throw Error("min level " + std::to_string(o.min_level) + " above max level " +
                    std::to_string(o.max_level));
    if (o.max_points < 1) throw Error("max points per leaf must be at least 1");
    if (!(o.smoothing > 0.0f) || !std::isfinite(o.smoothing) || o.smoothing > 1000.0f)
        throw Error("smoothing must be in (0, 1000]");
    if (!(o.support >= 1.0f) || !(o.support <= 10.0f)) throw Error("support must be in [1, 10] sigmas");
    if (o.knn < 1 || o.knn > 1024) throw Error("k of the k-NN radius must be in [1, 1024]");
    if (!(o.knn_clamp == 0.0f || (o.knn_clamp >= 1.0f && std::isfinite(o.knn_clamp))))
        throw Error("the k-NN clamp factor must be 0 (off) or at least 1");
    if (!(o.data_reach == 0.0f || (o.data_reach >= 0.25f && o.data_reach <= 3.0f)))
        throw Error("the data reach must be 0 (off) or in [0.25, 3] radii");
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

using Progress = std::function<void(const char*, std::uint64_t, std::uint64_t)>;

/// Leaf kinds (thesis 4.3.1) and the internal-node marker. k_untested: a new leaf without points
/// whose disk test (passive or empty) the 2:1 balance runs later, in parallel (TreeBuilder::DiskTest).
enum Kind : std::uint8_t { k_empty = 0, k_active = 1, k_passive = 2, k_internal = 3, k_untested = 4 };

/// A node of the octree under construction.
struct Node {
    std::uint32_t child = 0;  ///< first of 8 children; 0 for a leaf (the root is never a child)
    std::uint32_t parent = 0;
    std::uint32_t begin = 0, end = 0;   ///< its points, in code order
    std::uint32_t x = 0, y = 0, z = 0;  ///< cell at `level`
    std::uint8_t level = 0;
    std::uint8_t kind = k_empty;
};

bool is_filled(std::uint8_t kind) {
    return kind == k_active || kind == k_passive;
}

/// Sets every element of `v` to `value`, from `threads` workers (the large index tables).
template <class Vector>
void fill_parallel(Vector& v, typename Vector::value_type value, unsigned threads) {
    parallel_chunks(v.size(), 1 << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::fill(v.begin() + static_cast<std::ptrdiff_t>(b), v.begin() + static_cast<std::ptrdiff_t>(e),
                  value);
    });
}

/// The usable points, sorted by their level-K Morton code (structure of arrays). Buffers: the
/// parallel fill of sorted_points touches their pages first, not a serial zeroing (120 MB at 1M points).
struct PointSet {
    std::size_t n = 0;
    pre::Buffer<double> pos, nrm;     ///< 3n: position (local frame), unit normal
    pre::Buffer<double> sigma;        ///< Gaussian sigma_i
    pre::Buffer<double> inv2s2;       ///< 1 / (2 sigma_i^2)
    pre::Buffer<double> wn;           ///< eq. 4.1's normalization 1 / sqrt(2 pi sigma_i^2)
    pre::Buffer<double> log_sigma;    ///< log sigma_i (far corners' log weights)
    pre::Buffer<double> support;      ///< support x sigma_i: the corner evaluation's reach
    pre::Buffer<double> rho;          ///< radius of the influence disk (passive leaves)
    pre::Buffer<double> reach;        ///< max(support, rho): what the index is built for
    pre::Buffer<double> data2;        ///< (data_reach x r_i)^2: how far from p_i the data "is" (issue 15)
    pre::Buffer<std::uint8_t> col;    ///< 3n sRGB
    pre::Buffer<std::uint64_t> code;  ///< sorted
};

/// Points grouped by the size of their reach, each group sorted by code (so that a box query
/// widens the box only by its own group's largest reach).
struct ClassIndex {
    std::uint32_t level = 0;  ///< cells at least as wide as the group's largest reach
    double reach = 0;
    pre::LargeVector<std::uint64_t> codes;
    pre::LargeVector<std::uint32_t> ids;  ///< into PointSet
};

struct InfluenceIndex {
    Frame frame;
    std::vector<ClassIndex> classes;
};

InfluenceIndex build_index(const PointSet& ps, const Frame& frame, unsigned threads) {
    InfluenceIndex index;
    index.frame = frame;
    if (ps.n == 0) return index;
    std::vector<double> sorted(ps.reach.begin(), ps.reach.end());
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const std::uint32_t median_level =
        detail::level_for_extent(frame, sorted[sorted.size() / 2], 1.0, k_code_level);
    const std::uint32_t finest = std::min(k_code_level, median_level + 2);
    // Each point's class (the level of its reach, at most `finest`); classes in the order of their
    // first point, each holding its points in point order. Per chunk in parallel: levels, counts,
    // first points and largest reaches; then each chunk writes its points at its offsets.
    constexpr std::size_t k_chunk = 1u << 15;
    constexpr std::size_t k_levels = k_code_level + 1;
    const std::size_t chunks = (ps.n + k_chunk - 1) / k_chunk;
    std::vector<std::uint8_t> level_of(ps.n);
    std::vector<std::array<std::size_t, k_levels>> count(chunks);
    std::vector<std::array<std::size_t, k_levels>> first(chunks);
    std::vector<std::array<double, k_levels>> reach(chunks);
    parallel_chunks(ps.n, k_chunk, threads, [&](std::size_t b, std::size_t e, unsigned) {
        const std::size_t k = b / k_chunk;
        count[k].fill(0);
        first[k].fill(SIZE_MAX);
        reach[k].fill(0.0);
        for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t level =
                std::min(finest, detail::level_for_extent(frame, ps.reach[i], 1.0, k_code_level));
            level_of[i] = static_cast<std::uint8_t>(level);
            if (count[k][level]++ == 0) first[k][level] = i;
            reach[k][level] = std::max(reach[k][level], ps.reach[i]);
        }
    });
    std::array<std::size_t, k_levels> level_first;
    level_first.fill(SIZE_MAX);
    std::array<std::size_t, k_levels> total{};
    for (std::size_t k = 0; k < chunks; ++k)
        for (std::size_t l = 0; l < k_levels; ++l) {
            level_first[l] = std::min(level_first[l], first[k][l]);
            total[l] += count[k][l];
        }
    std::vector<std::uint32_t> levels;  // in the order of their first point
    for (std::uint32_t l = 0; l < k_levels; ++l)
        if (total[l] > 0) levels.push_back(l);
    std::sort(levels.begin(), levels.end(),
              [&](std::uint32_t a, std::uint32_t b) { return level_first[a] < level_first[b]; });
    std::array<int, k_levels> slot;
    slot.fill(-1);
    index.classes.resize(levels.size());
    for (std::size_t c = 0; c < levels.size(); ++c) {
        const std::uint32_t l = levels[c];
        slot[l] = static_cast<int>(c);
        ClassIndex& ci = index.classes[c];
        ci.level = l;
        for (std::size_t k = 0; k < chunks; ++k) ci.reach = std::max(ci.reach, reach[k][l]);
        ci.codes.resize(total[l]);
        ci.ids.resize(total[l]);
    }
    // offsets: count[k][l] becomes where chunk k's points of level l start in their class
    for (std::size_t l = 0; l < k_levels; ++l) {
        std::size_t at = 0;
        for (std::size_t k = 0; k < chunks; ++k) std::swap(at, count[k][l]), at += count[k][l];
    }
    parallel_chunks(ps.n, k_chunk, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::array<std::size_t, k_levels>& at = count[b / k_chunk];
        for (std::size_t i = b; i < e; ++i) {
            ClassIndex& ci = index.classes[slot[level_of[i]]];
            const std::size_t j = at[level_of[i]]++;
            ci.codes[j] = ps.code[i];
            ci.ids[j] = static_cast<std::uint32_t>(i);
        }
    });
    return index;
}

/// Squared distance from point p to the box [lo, hi].
double box_distance_sq(const double* p, const double lo[3], const double hi[3]) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
        const double d = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0.0);
        d2 += d * d;
    }
    return d2;
}

/// Appends the points whose ball of radius radius[i] meets the box [lo, hi] (exact test).
void gather_overlapping(const InfluenceIndex& index, const PointSet& ps, const pre::Buffer<double>& radius,
                        const double lo[3], const double hi[3], std::vector<std::uint32_t>& out) {
    for (const ClassIndex& c : index.classes) {
        double blo[3], bhi[3], extent = 0;
        for (int a = 0; a < 3; ++a) {
            blo[a] = lo[a] - c.reach;
            bhi[a] = hi[a] + c.reach;
            extent = std::max(extent, bhi[a] - blo[a]);
        }
        const std::uint32_t level =
            std::min(c.level, detail::level_for_extent(index.frame, extent, 4.0, k_code_level));
        detail::for_each_node_range(c.codes, index.frame, level, blo, bhi, [&](std::size_t b, std::size_t e) {
            for (std::size_t k = b; k < e; ++k) {
                const std::uint32_t id = c.ids[k];
                const double r = radius[id];
                if (box_distance_sq(&ps.pos[3 * id], lo, hi) <= r * r) out.push_back(id);
            }
        });
    }
}

/// Appends the points within distance `radius` of q (exact test).
void gather_ball(const InfluenceIndex& index, const PointSet& ps, const double q[3], double radius,
                 std::vector<std::uint32_t>& out) {
    const double r2 = radius * radius;
    double blo[3], bhi[3];
    for (int a = 0; a < 3; ++a) blo[a] = q[a] - radius, bhi[a] = q[a] + radius;
    for (const ClassIndex& c : index.classes) {
        const std::uint32_t level =
            std::min(c.level, detail::level_for_extent(index.frame, 2 * radius, 4.0, k_code_level));
        detail::for_each_node_range(c.codes, index.frame, level, blo, bhi, [&](std::size_t b, std::size_t e) {
            for (std::size_t k = b; k < e; ++k) {
                const std::uint32_t id = c.ids[k];
                const double* p = &ps.pos[3 * id];
                const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                  (p[2] - q[2]) * (p[2] - q[2]);
                if (d2 <= r2) out.push_back(id);
            }
        });
    }
}

// ---- radii of influence: k nearest neighbours (thesis 3.1, as prt-radii) ----------------------

/// Distance from every point to its k-th nearest other point (exact: the shared kd-tree in double).
pre::LargeVector<double> knn_distances(const std::vector<double>& pos, std::uint32_t k, unsigned threads,
                                       const Progress& progress) {
    const std::size_t n = pos.size() / 3;
    if (n <= k)
        throw Error("the k-NN radius needs more than k = " + std::to_string(k) + " points, the model has " +
                    std::to_string(n));
    const pre::KdTree<double> tree(
        n, [&](std::size_t i, double c[3]) { std::copy_n(&pos[3 * i], 3, c); }, threads);
    pre::LargeVector<double> result(n);
    tree.for_each(
        k, threads,
        [&](std::uint32_t i, const std::uint32_t*, const double* distance2, std::uint32_t) {
            result[i] = std::sqrt(distance2[k - 1]);
        },
        [&](std::uint64_t done) {
            if (progress) progress("k-NN radii", done, n);
        });
    return result;
}

// ---- the octree over the points (thesis 4.3.1) --------------------------------------------------

class TreeBuilder {
public:
    TreeBuilder(const PointSet& ps, const InfluenceIndex& index, const Frame& frame, const BuildOptions& o)
        : m_ps(ps), m_index(index), m_frame(frame), m_options(o) {}

    pre::LargeVector<Node> nodes;

    void check_size(std::size_t more) const {
        if (nodes.size() + more > pool::k_node_address_max)
            throw Error(
                "the ISO octree would need more than 2^30 nodes (lower --max-level or raise --max-points)");
    }

    /// The node holding cell (x, y, z) at `level`, or the leaf above it.
    std::uint32_t locate(const std::uint32_t cell[3], std::uint32_t level) const {
        return locate_from(0, cell, level);
    }

    /// locate(cell, level), descending from `node`: a node that held the cell at a level <= `level`
    /// (an earlier answer stays one: splits only turn leaves into internal nodes).
    std::uint32_t locate_from(std::uint32_t node, const std::uint32_t cell[3], std::uint32_t level) const {
        while (nodes[node].child != 0 && nodes[node].level < level) {  // bounded: one level per step
            const std::uint32_t s = level - nodes[node].level - 1;
            node = nodes[node].child +
                   (((cell[0] >> s) & 1u) | (((cell[1] >> s) & 1u) << 1) | (((cell[2] >> s) & 1u) << 2));
        }
        return node;
    }

    /// Top-down split by point count (step 2), one level at a time: the splits of a level are
    /// independent, so they run in parallel, and their children are appended in the parents'
    /// order, which gives the breadth-first node order (and tree) of splitting one node at a time.
    void build_from_points(unsigned threads) {
        nodes.clear();
        Node root;
        root.begin = 0;
        root.end = static_cast<std::uint32_t>(m_ps.n);
        root.kind = m_ps.n > 0 ? k_active : k_empty;
        nodes.push_back(root);
        auto splits = [&](const Node& n) {
            const std::uint32_t count = n.end - n.begin;
            return count > 0 && (n.level < m_options.min_level ||
                                 (n.level < m_options.max_level && count > m_options.max_points));
        };
        std::vector<std::uint32_t> parents;
        for (std::size_t begin = 0, end = 1; begin < end; begin = end, end = nodes.size()) {
            parents.resize(end - begin);
            parents.resize(parallel_select(
                end - begin, threads, [&](std::size_t k) { return splits(nodes[begin + k]); },
                [&](std::size_t rank, std::size_t k) {
                    parents[rank] = static_cast<std::uint32_t>(begin + k);
                }));
            check_size(8 * parents.size());
            pre::resize_prefaulted(nodes, end + 8 * parents.size(), threads);
            parallel_chunks(parents.size(), 256, threads, [&](std::size_t b, std::size_t e, unsigned) {
                for (std::size_t r = b; r < e; ++r)
                    make_children(parents[r], static_cast<std::uint32_t>(end + 8 * r));
            });
        }
    }

    /// What split_by_points does with children without points: leave them empty (none), test them
    /// against the influence disks near the parent now (passive or empty), or mark them k_untested
    /// for test_untested (later).
    enum class DiskTest { none, now, later };

    /// Splits leaf `i` into 8 children: children with points are active; the others as `disks`
    /// says. Returns the first child.
    std::uint32_t split_by_points(std::uint32_t i, DiskTest disks) {
        check_size(8);
        const std::uint32_t first = static_cast<std::uint32_t>(nodes.size());
        nodes.resize(first + 8);
        make_children(i, first, disks);
        if (disks == DiskTest::now) test_children(i, m_candidates);
        if (disks == DiskTest::later) m_untested.push_back(i);
        return first;
    }

    /// Writes the 8 children of leaf `i` at nodes[first, first + 8) (allocated) and makes `i` their
    /// parent: each child gets the points of its octant (the codes are sorted); a child without
    /// points is empty or, unless `disks` is none, k_untested.
    void make_children(std::uint32_t i, std::uint32_t first, DiskTest disks = DiskTest::none) {
        const Node parent = nodes[i];
        const std::uint32_t shift = 3 * (k_code_level - parent.level - 1);
        const std::uint64_t* code = m_ps.code.data();
        std::uint32_t b = parent.begin;
        for (std::uint32_t c = 0; c < 8; ++c) {
            const std::uint32_t e = static_cast<std::uint32_t>(
                std::partition_point(code + b, code + parent.end,
                                     [&](std::uint64_t k) { return ((k >> shift) & 7u) <= c; }) -
                code);
            Node& child = nodes[first + c];
            child = Node{};
            child.parent = i;
            child.begin = b;
            child.end = e;
            child.level = static_cast<std::uint8_t>(parent.level + 1);
            child.x = 2 * parent.x + (c & 1u);
            child.y = 2 * parent.y + ((c >> 1) & 1u);
            child.z = 2 * parent.z + ((c >> 2) & 1u);
            child.kind = b < e ? k_active : (disks == DiskTest::none ? k_empty : k_untested);
            b = e;
        }
        nodes[i].child = first;
        nodes[i].kind = k_internal;
    }

    /// The k_untested children of `parent` become passive where a point's influence disk overlaps
    /// them (thesis 4.3.1), else empty. `candidates`: scratch. Writes only those children.
    void test_children(std::uint32_t parent, std::vector<std::uint32_t>& candidates) {
        const Node p = nodes[parent];
        bool any = false;
        for (std::uint32_t c = 0; c < 8; ++c) any |= nodes[p.child + c].kind == k_untested;
        if (!any) return;
        double lo[3], hi[3];
        m_frame.box(p.level, p.x, p.y, p.z, lo, hi);
        candidates.clear();
        gather_overlapping(m_index, m_ps, m_ps.rho, lo, hi, candidates);
        for (std::uint32_t c = 0; c < 8; ++c) {
            Node& ch = nodes[p.child + c];
            if (ch.kind != k_untested) continue;
            ch.kind = k_empty;
            double clo[3], chi[3];
            m_frame.box(ch.level, ch.x, ch.y, ch.z, clo, chi);
            for (std::uint32_t id : candidates)
                if (pre::disk_overlaps_box(&m_ps.pos[3 * id], &m_ps.nrm[3 * id], m_ps.rho[id], clo, chi)) {
                    ch.kind = k_passive;
                    break;
                }
        }
    }

    /// test_children for every parent split with DiskTest::later so far, in parallel.
    void test_untested(unsigned threads) {
        parallel_chunks(m_untested.size(), 64, threads, [&](std::size_t b, std::size_t e, unsigned) {
            std::vector<std::uint32_t> candidates;
            for (std::size_t k = b; k < e; ++k) test_children(m_untested[k], candidates);
        });
        m_untested.clear();
    }

    /// thesis 4.3.1: marks empty leaves touched by a point's influence disk as passive.
    void mark_passive(unsigned threads, const Progress& progress) {
        std::atomic<std::uint64_t> done{0};
        parallel_chunks(m_ps.n, 4096, threads, [&](std::size_t b, std::size_t e, unsigned worker) {
            std::uint32_t stack[8 * (pool::k_max_iso_level + 2)];
            for (std::size_t i = b; i < e; ++i) {
                const double* p = &m_ps.pos[3 * i];
                const double* nv = &m_ps.nrm[3 * i];
                const double r = m_ps.rho[i];
                double dlo[3], dhi[3];
                std::uint32_t clo[3], chi[3];
                for (int a = 0; a < 3; ++a) {
                    const double h = pre::disk_half_extent(r, nv[a]);
                    dlo[a] = p[a] - h;
                    dhi[a] = p[a] + h;
                    clo[a] = m_frame.cell(dlo[a], a, k_code_level);
                    chi[a] = m_frame.cell(dhi[a], a, k_code_level);
                }
                const std::uint64_t diff = morton3(clo[0], clo[1], clo[2]) ^ morton3(chi[0], chi[1], chi[2]);
                // Levels whose child choice is the same for both corners of the disk's box.
                const std::uint32_t common =
                    diff == 0 ? k_code_level : k_code_level - 1 - (63 - std::countl_zero(diff)) / 3;
                const std::uint64_t code = m_ps.code[i];
                std::uint32_t node = 0;
                while (nodes[node].child != 0 && nodes[node].level < common)
                    node = nodes[node].child +
                           static_cast<std::uint32_t>((code >> (3 * (k_code_level - nodes[node].level - 1))) &
                                                      7u);
                if (nodes[node].child == 0) continue;  // a leaf holds the whole disk: p's own, active
                std::uint32_t top = 0;
                stack[top++] = node;
                while (top > 0) {  // bounded: at most 8 entries per level on the stack
                    const Node& nd = nodes[stack[--top]];
                    for (std::uint32_t c = 0; c < 8; ++c) {
                        const std::uint32_t ci = nd.child + c;
                        const Node& ch = nodes[ci];
                        double lo[3], hi[3];
                        m_frame.box(ch.level, ch.x, ch.y, ch.z, lo, hi);
                        if (lo[0] > dhi[0] || hi[0] < dlo[0] || lo[1] > dhi[1] || hi[1] < dlo[1] ||
                            lo[2] > dhi[2] || hi[2] < dlo[2])
                            continue;
                        if (ch.child != 0) {
                            stack[top++] = ci;
                            continue;
                        }
                        std::atomic_ref<std::uint8_t> kind(nodes[ci].kind);
                        if (kind.load(std::memory_order_relaxed) != k_empty) continue;
                        if (pre::disk_overlaps_box(p, nv, r, lo, hi))
                            kind.store(k_passive, std::memory_order_relaxed);
                    }
                }
            }
            const std::uint64_t d = done.fetch_add(e - b) + (e - b);
            if (worker == 0 && progress) progress("passive leaves", d, m_ps.n);
        });
    }

    /// Splits passive leaves above min_level down to it (their children tested against the disks).
    std::uint64_t enforce_min_level() {
        std::uint64_t splits = 0;
        if (m_options.min_level == 0) return splits;      // no level is above it
        for (std::size_t i = 0; i < nodes.size(); ++i) {  // children appended behind are visited too
            if (nodes[i].child == 0 && nodes[i].kind == k_passive && nodes[i].level < m_options.min_level) {
                split_by_points(static_cast<std::uint32_t>(i), DiskTest::now);
                ++splits;
            }
        }
        return splits;
    }

    /// thesis 4.5.1: 2:1 balance. For every filled leaf B at level l (finest levels first), the
    /// cells next to B (faces, edges, corners) must lie in nodes of level >= l - 1; a filled leaf
    /// coarser than that is split (repeatedly) until they do. B's neighbour cells at level l - 1
    /// are its parent's neighbours on B's sides, so the check runs once per parent and direction.
    /// In parallel: which (parent, direction) pairs need a split at all (most need none, and a
    /// pair that needs none still needs none after other pairs' splits: splits only refine filled
    /// leaves, which such a pair's descent does not meet), and the disk tests of the new leaves
    /// (DiskTest::later, run before the next level reads them). The splits themselves run in the
    /// serial order, so the tree is the one a serial pass builds.
    std::uint64_t balance(unsigned threads, const Progress& progress) {
        std::uint64_t splits = 0;
        // Room for the splits below (one at a time, serial order) without a copy on this thread.
        pre::reserve_prefaulted(nodes, nodes.size() + nodes.size() / 2, threads);
        // Filled leaves by level in node order (per chunk in parallel, then joined in chunk order);
        // each level's splits add their filled leaves.
        constexpr std::size_t k_chunk = 1u << 16;
        const std::size_t chunks = (nodes.size() + k_chunk - 1) / k_chunk;
        std::vector<std::array<std::vector<std::uint32_t>, pool::k_max_iso_level + 1>> chunk_levels(chunks);
        parallel_chunks(nodes.size(), k_chunk, threads, [&](std::size_t b, std::size_t e, unsigned) {
            auto& mine = chunk_levels[b / k_chunk];
            for (std::size_t i = b; i < e; ++i)
                if (nodes[i].child == 0 && is_filled(nodes[i].kind))
                    mine[nodes[i].level].push_back(static_cast<std::uint32_t>(i));
        });
        std::uint32_t deepest = 0;
        for (const Node& n : nodes) deepest = std::max<std::uint32_t>(deepest, n.level);
        std::vector<std::vector<std::uint32_t>> by_level(deepest + 1);
        for (std::uint32_t l = 0; l <= deepest; ++l)
            for (const auto& c : chunk_levels)
                by_level[l].insert(by_level[l].end(), c[l].begin(), c[l].end());
        chunk_levels.clear();
        for (std::uint32_t l = deepest; l >= 2; --l) {
            // Parents of filled leaves at level l, with the directions their filled children face,
            // one entry per run of leaves with the same parent (in by_level's order): each leaf's
            // parent and mask in parallel, then the runs' starts, then each run's masks joined.
            std::vector<std::pair<std::uint32_t, std::uint32_t>> leaf_work(by_level[l].size());
            leaf_work.resize(parallel_select(
                by_level[l].size(), threads,
                [&](std::size_t k) { return nodes[by_level[l][k]].child == 0; },  // else split since
                [&](std::size_t rank, std::size_t k) {
                    const std::uint32_t i = by_level[l][k];
                    const Node& n = nodes[i];
                    const std::uint32_t c = i - nodes[n.parent].child;
                    std::uint32_t mask = 0;
                    const int sx = (c & 1u) ? 1 : -1, sy = (c & 2u) ? 1 : -1, sz = (c & 4u) ? 1 : -1;
                    for (int dz = 0; dz < 2; ++dz)
                        for (int dy = 0; dy < 2; ++dy)
                            for (int dx = 0; dx < 2; ++dx) {
                                if (dx == 0 && dy == 0 && dz == 0) continue;
                                const int d = (dx * sx + 1) + 3 * (dy * sy + 1) + 9 * (dz * sz + 1);
                                mask |= 1u << d;
                            }
                    leaf_work[rank] = {n.parent, mask};
                }));
            std::vector<std::uint32_t> run_start(leaf_work.size() + 1);
            run_start.resize(parallel_select(
                leaf_work.size(), threads,
                [&](std::size_t k) { return k == 0 || leaf_work[k].first != leaf_work[k - 1].first; },
                [&](std::size_t rank, std::size_t k) { run_start[rank] = static_cast<std::uint32_t>(k); }));
            run_start.push_back(static_cast<std::uint32_t>(leaf_work.size()));
            std::vector<std::pair<std::uint32_t, std::uint32_t>> work(run_start.size() - 1);
            parallel_chunks(work.size(), 4096, threads, [&](std::size_t b, std::size_t e, unsigned) {
                for (std::size_t r = b; r < e; ++r) {
                    work[r] = {leaf_work[run_start[r]].first, 0u};
                    for (std::uint32_t k = run_start[r]; k < run_start[r + 1]; ++k)
                        work[r].second |= leaf_work[k].second;
                }
            });
            // The neighbour cell of `parent` in direction d, if inside the root.
            auto neighbour = [&](const Node& p, int d, std::uint32_t cell[3]) {
                const std::int64_t top = std::int64_t{1} << p.level;
                const std::int64_t c[3] = {std::int64_t{p.x} + d % 3 - 1, std::int64_t{p.y} + (d / 3) % 3 - 1,
                                           std::int64_t{p.z} + d / 9 - 1};
                for (int a = 0; a < 3; ++a) {
                    if (c[a] < 0 || c[a] >= top) return false;
                    cell[a] = static_cast<std::uint32_t>(c[a]);
                }
                return true;
            };
            parallel_chunks(work.size(), 1024, threads, [&](std::size_t b, std::size_t e, unsigned) {
                for (std::size_t k = b; k < e; ++k) {
                    const Node& p = nodes[work[k].first];
                    std::uint32_t needed = 0;
                    for (int d = 0; d < 27; ++d) {
                        std::uint32_t cell[3];
                        if ((work[k].second & (1u << d)) && neighbour(p, d, cell) &&
                            needs_split(cell, p.level))
                            needed |= 1u << d;
                    }
                    work[k].second = needed;
                }
            });
            const std::size_t before = nodes.size();
            for (const auto& [parent, mask] : work) {
                for (int d = 0; d < 27 && mask != 0; ++d) {
                    std::uint32_t cell[3];
                    if (!(mask & (1u << d)) || !neighbour(nodes[parent], d, cell)) continue;
                    splits += refine_towards(cell[0], cell[1], cell[2], nodes[parent].level);
                }
            }
            test_untested(threads);
            for (std::size_t i = before; i < nodes.size(); ++i)
                if (nodes[i].child == 0 && is_filled(nodes[i].kind))
                    by_level[nodes[i].level].push_back(static_cast<std::uint32_t>(i));
            if (progress) progress("2:1 balance", deepest - l + 1, deepest - 1);
        }
        return splits;
    }

private:
    /// Descends towards the cell (x, y, z) at `level`, splitting every filled leaf met above that
    /// level. Returns the number of splits.
    std::uint64_t refine_towards(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint32_t level) {
        std::uint64_t splits = 0;
        std::uint32_t node = 0;
        for (;;) {  // bounded: one level per iteration
            if (nodes[node].level >= level) break;
            if (nodes[node].child == 0) {
                if (nodes[node].kind == k_untested) test_children(nodes[node].parent, m_candidates);
                if (!is_filled(nodes[node].kind)) break;
                split_by_points(node, m_options.passive ? DiskTest::later : DiskTest::none);
                ++splits;
            }
            const std::uint32_t s = level - nodes[node].level - 1;
            const std::uint32_t c = ((x >> s) & 1u) | (((y >> s) & 1u) << 1) | (((z >> s) & 1u) << 2);
            node = nodes[node].child + c;
        }
        return splits;
    }

    /// Whether refine_towards(cell, level) would split a leaf (read only).
    bool needs_split(const std::uint32_t cell[3], std::uint32_t level) const {
        const Node& n = nodes[locate(cell, level)];
        return n.level < level && is_filled(n.kind);
    }

    const PointSet& m_ps;
    const InfluenceIndex& m_index;
    const Frame& m_frame;
    const BuildOptions& m_options;
    std::vector<std::uint32_t> m_candidates;
    std::vector<std::uint32_t> m_untested;  ///< parents split with DiskTest::later, not yet tested
};

// ---- surface closure (thesis 4.3.1, 4.5.1) --------------------------------------------------------

/// Passive leaves found by disks miss cells where the smoothed surface f = 0 leaves every disk
/// (noisy scans, coarse levels of detail) and rays then fall through holes. The corner values
/// say where the surface goes: a filled leaf whose face has corners of both signs is crossed by
/// its trilinear surface there, so the leaves on the other side of that face must be filled too:
///   same-level empty leaf  -> filled (passive);
///   coarser empty leaf     -> split down to the level, the cell on the face filled;
///   finer empty leaves     -> those touching the face where the leaf's surface crosses it
///                             (its trilinear f has both signs at their corners on the face);
///   coarser filled leaf without a sign change -> split, its children filled (it is too coarse to
///                             hold the surface its finer neighbour reaches it with).
/// Only cells some point's support reaches are filled this way: f far from every point says
/// little, and on scans with inconsistent normals its sign flips there and would flood the volume.
/// New leaves are evaluated and examined in turn until no face leads anywhere new. The 2:1 balance
/// (thesis 4.5.1) is kept: a new leaf with a filled neighbour two or more levels coarser splits
/// that neighbour, one with a filled leaf two or more levels finer next to it splits itself.
/// Leaves that still end up without a sign change are dropped like any other.
class SurfaceClosure {
public:
    /// Whether some point's support reaches cell (x, y, z) at `level` (a function of the cell
    /// only); the vector is the caller's scratch (calls run in parallel).
    using Near = std::function<bool(std::uint32_t level, std::uint32_t x, std::uint32_t y, std::uint32_t z,
                                    std::vector<std::uint32_t>& scratch)>;
    SurfaceClosure(TreeBuilder& tree, std::uint32_t max_level, Near near, bool serial_only = false)
        : m_tree(tree), m_max_level(max_level), m_near(std::move(near)), m_serial_only(serial_only) {}

    /// Examines the faces of `frontier` (evaluated leaves); returns the leaves to evaluate next.
    /// `values(node, f)` fills the 8 corner values of an evaluated leaf; `sign_mask` and `values`
    /// are called from `threads` workers at once.
    /// In parallel first: which faces can lead anywhere. A face the surface crosses into a filled
    /// leaf of the same level leads nowhere, whatever the serial pass adds or splits before it
    /// gets there (a split of that leaf gives filled children only); nor does one into an empty
    /// leaf (of its level or coarser) when no support reaches the cell beyond the face at the
    /// face's level (m_near, a function of the cell: then none reaches any cell inside it, which
    /// is all the serial pass could fill there); nor does one into finer leaves when no empty leaf
    /// on the face has corners of both signs under the leaf's trilinear f (face_signs): the
    /// serial pass only fills or splits leaves there, and a split leaf's face corners lie on its
    /// face, where f (bilinear on the plane, so between its corner values) keeps their sign; faces
    /// with a corner value near 0, where rounding could differ, stay open. Only the other faces go
    /// through beyond_face, in the serial order, with m_near's answer where it was asked (on the
    /// 1M room, 485k faces into finer leaves went through the serial pass and 4k of their empty
    /// leaves had both signs).
    template <class SignMask, class Values>
    std::vector<std::uint32_t> close(const std::vector<std::uint32_t>& frontier,
                                     const pre::LargeVector<std::uint32_t>& leaf_slot, SignMask&& sign_mask,
                                     Values&& values, unsigned threads) {
        pre::LargeVector<Node>& nodes = m_tree.nodes;
        m_added.clear();
        m_work.clear();
        auto evaluated = [&](std::uint32_t i) { return i < leaf_slot.size() && leaf_slot[i] != UINT32_MAX; };
        // Bit 2a + side: the surface crosses that face (corners of both signs on it).
        auto crossed_faces = [&](std::uint32_t leaf) {
            if (nodes[leaf].child != 0 || !evaluated(leaf)) return 0u;
            const std::uint32_t m = sign_mask(leaf);
            if (m == 0 || m == 0xffu) return 0u;
            std::uint32_t faces = 0;
            for (std::uint32_t a = 0; a < 3; ++a)
                for (std::uint32_t side = 0; side < 2; ++side) {
                    std::uint32_t face = 0;  // corners on this face
                    for (std::uint32_t c = 0; c < 8; ++c)
                        if (((c >> a) & 1u) == side) face |= 1u << c;
                    if ((m & face) != 0 && (m & face) != face) faces |= 1u << (2 * a + side);
                }
            return faces;
        };
        std::vector<std::uint8_t> open(frontier.size()), near(frontier.size());  // face bits
        // The node locate() gave for each open face: the serial pass goes on from there instead of
        // descending from the root again (a cache miss per level: 30 % of that pass's time).
        pre::Buffer<std::uint32_t> located(6 * frontier.size());
        parallel_chunks(frontier.size(), 1024, threads, [&](std::size_t b, std::size_t e, unsigned) {
            std::vector<std::uint32_t> scratch, stack;
            for (std::size_t k = b; k < e; ++k) {
                const std::uint32_t leaf = frontier[k], l = nodes[leaf].level;
                std::uint32_t faces = crossed_faces(leaf), near_faces = 0;
                for (std::uint32_t f = 0; f < 6; ++f) {
                    std::uint32_t cell[3];
                    if (!(faces & (1u << f))) continue;
                    if (!neighbour_cell(leaf, f / 2, f % 2, cell)) {
                        faces &= ~(1u << f);  // the root's face
                        continue;
                    }
                    located[6 * k + f] = m_tree.locate(cell, l);
                    if (m_serial_only) continue;  // BuildOptions::closure_serial_only (tests)
                    const std::uint32_t beyond = located[6 * k + f];
                    const Node& n = nodes[beyond];
                    if (n.child != 0) {  // finer leaves beyond: the serial pass decides, if one may be filled
                        double v[8];
                        values(leaf, v);
                        if (!mixed_empty_on_face(leaf, v, beyond, f / 2, f % 2, stack)) faces &= ~(1u << f);
                        continue;
                    }
                    if (n.kind != k_empty) {
                        // The same level, or a coarser leaf with a sign change or not evaluated yet:
                        // the serial pass leaves it as it is (it splits filled leaves only when they
                        // are evaluated and uncrossed, and such a leaf stays one until this round ends).
                        const std::uint32_t m = evaluated(beyond) ? sign_mask(beyond) : 0x100u;
                        if (n.level == l || (m != 0 && m != 0xffu)) faces &= ~(1u << f);
                    } else if (m_near(l, cell[0], cell[1], cell[2], scratch)) {
                        near_faces |= 1u << f;
                    } else {
                        faces &= ~(1u << f);
                    }
                }
                open[k] = static_cast<std::uint8_t>(faces);
                near[k] = static_cast<std::uint8_t>(near_faces);
            }
        });
        for (std::size_t k = 0; k < frontier.size(); ++k) {
            if (open[k] == 0) continue;
            const std::uint32_t leaf = frontier[k];
            if (nodes[leaf].child != 0) continue;  // split by an earlier face
            for (std::uint32_t a = 0; a < 3; ++a)
                for (std::uint32_t side = 0; side < 2; ++side) {
                    const std::uint32_t bit = 1u << (2 * a + side);
                    if (!(open[k] & bit)) continue;
                    beyond_face(
                        leaf, a, side, located[6 * k + 2 * a + side], (near[k] & bit) != 0,
                        [&](std::uint32_t i) {
                            return evaluated(i) ? sign_mask(i) : 0x100u;  // 0x100: not known yet
                        },
                        values);
                }
        }
        keep_balanced();
        std::vector<std::uint32_t> out;
        for (const std::uint32_t i : m_added)
            if (nodes[i].child == 0) out.push_back(i);
        return out;
    }

private:
    /// Marks leaf i filled and to be evaluated (and balanced).
    void add(std::uint32_t i) {
        Node& n = m_tree.nodes[i];
        if (n.kind == k_empty) n.kind = k_passive;
        m_added.push_back(i);
        m_work.push_back(i);
    }

    /// Fills empty leaf i if some point's support reaches it.
    void add_empty(std::uint32_t i) {
        const Node& n = m_tree.nodes[i];
        if (m_near(n.level, n.x, n.y, n.z, m_scratch)) add(i);
    }

    /// Splits filled leaf i; all 8 children are filled and to be evaluated.
    void split_all(std::uint32_t i) {
        const std::uint32_t first = m_tree.split_by_points(i, TreeBuilder::DiskTest::none);
        for (std::uint32_t c = 0; c < 8; ++c) add(first + c);
    }

    /// Trilinear interpolation of 8 corner values at unit-cube coordinates u (double).
    static double trilinear(const double c[8], const double u[3]) {
        const double x00 = c[0] + (c[1] - c[0]) * u[0], x10 = c[2] + (c[3] - c[2]) * u[0];
        const double x01 = c[4] + (c[5] - c[4]) * u[0], x11 = c[6] + (c[7] - c[6]) * u[0];
        const double y0 = x00 + (x10 - x00) * u[1], y1 = x01 + (x11 - x01) * u[1];
        return y0 + (y1 - y0) * u[2];
    }

    /// The cell beyond face (a, side) of `leaf`, at its level; false at the root's faces.
    bool neighbour_cell(std::uint32_t leaf, std::uint32_t a, std::uint32_t side,
                        std::uint32_t cell[3]) const {
        const Node& n = m_tree.nodes[leaf];
        cell[0] = n.x, cell[1] = n.y, cell[2] = n.z;
        if (side == 1) {
            if (cell[a] + 1 >= (1u << n.level)) return false;
            ++cell[a];
        } else {
            if (cell[a] == 0) return false;
            --cell[a];
        }
        return true;
    }

    /// `located`: a node that held the cell beyond the face (an earlier locate()'s answer);
    /// `near_known`: m_near is true for that cell at the leaf's level.
    template <class Mask, class Values>
    void beyond_face(std::uint32_t leaf, std::uint32_t a, std::uint32_t side, std::uint32_t located,
                     bool near_known, Mask&& mask, Values&& values) {
        pre::LargeVector<Node>& nodes = m_tree.nodes;
        const std::uint32_t l = nodes[leaf].level;
        std::uint32_t cell[3];
        if (!neighbour_cell(leaf, a, side, cell)) return;
        std::uint32_t node = m_tree.locate_from(located, cell, l);
        if (nodes[node].child == 0 && nodes[node].level == l) {
            if (nodes[node].kind == k_empty) {
                if (near_known)
                    add(node);
                else
                    add_empty(node);
            }
            return;
        }
        if (nodes[node].child == 0) {  // a coarser leaf
            if (nodes[node].kind == k_empty) {
                if (!near_known && !m_near(l, cell[0], cell[1], cell[2], m_scratch)) return;
                while (nodes[node].level < l) {  // bounded by l
                    m_tree.split_by_points(node, TreeBuilder::DiskTest::none);
                    node = m_tree.locate_from(node, cell, l);
                }
                add(node);
            } else {
                const std::uint32_t m = mask(node);
                if (m == 0 || m == 0xffu) split_all(node);
            }
            return;
        }
        // Finer leaves: those touching the shared face (child bit along a facing the leaf) where
        // the leaf's own trilinear f has both signs at their corners on that face.
        double f[8];
        values(leaf, f);
        const std::uint32_t facing = side == 1 ? 0u : 1u;
        std::vector<std::uint32_t> stack{node};
        while (!stack.empty()) {  // bounded by the subtree
            const std::uint32_t i = stack.back();
            stack.pop_back();
            if (nodes[i].child == 0) {
                if (nodes[i].kind != k_empty) continue;
                const FaceSigns signs = face_signs(leaf, f, i, a, side);
                if (signs.pos && signs.neg) add_empty(i);
                continue;
            }
            for (std::uint32_t c = 0; c < 8; ++c)
                if (((c >> a) & 1u) == facing) stack.push_back(nodes[i].child + c);
        }
    }

    /// The signs of `leaf`'s trilinear f (corner values `f`) at the 4 corners that leaf `i`, finer
    /// and beyond the leaf's face (a, side), has on that face: pos (some > 0), neg (some <= 0) and
    /// near_zero (some |value| within a rounding margin of 0: sum |f| x 2^-40).
    struct FaceSigns {
        bool pos = false, neg = false, near_zero = false;
    };
    FaceSigns face_signs(std::uint32_t leaf, const double f[8], std::uint32_t i, std::uint32_t a,
                         std::uint32_t side) const {
        const pre::LargeVector<Node>& nodes = m_tree.nodes;
        const std::uint32_t leaf_cell[3] = {nodes[leaf].x, nodes[leaf].y, nodes[leaf].z};
        const std::uint32_t e_cell[3] = {nodes[i].x, nodes[i].y, nodes[i].z};
        const double scale = std::ldexp(1.0, -static_cast<int>(nodes[i].level - nodes[leaf].level));
        double magnitude = 0;
        for (std::uint32_t c = 0; c < 8; ++c) magnitude += std::fabs(f[c]);
        const double margin = std::ldexp(magnitude, -40);
        FaceSigns out;
        for (std::uint32_t c = 0; c < 4; ++c) {  // the 4 corners of i on the face
            double u[3];
            std::uint32_t k = 0;
            for (std::uint32_t b = 0; b < 3; ++b) {
                if (b == a) {
                    u[b] = side;
                    continue;
                }
                u[b] = (e_cell[b] + ((c >> k++) & 1u)) * scale - leaf_cell[b];
            }
            const double v = trilinear(f, u);
            (v > 0 ? out.pos : out.neg) = true;
            if (std::fabs(v) <= margin) out.near_zero = true;
        }
        return out;
    }

    /// Whether beyond_face could fill a leaf of the subtree of node i, finer and beyond `leaf`'s
    /// face (a, side): some empty leaf touching that face (its children with bit a facing the leaf)
    /// has corners of both signs there under `leaf`'s trilinear f (values `f`), or one near 0. The
    /// serial pass adds no empty leaf there and splits only empty leaves, whose children's face
    /// corners lie on the split leaf's face, where f keeps the sign it has at its corners. `stack`:
    /// scratch.
    bool mixed_empty_on_face(std::uint32_t leaf, const double f[8], std::uint32_t i, std::uint32_t a,
                             std::uint32_t side, std::vector<std::uint32_t>& stack) const {
        const pre::LargeVector<Node>& nodes = m_tree.nodes;
        const std::uint32_t facing = side == 1 ? 0u : 1u;
        stack.assign(1, i);
        while (!stack.empty()) {  // bounded by the subtree
            const std::uint32_t k = stack.back();
            stack.pop_back();
            if (nodes[k].child == 0) {
                if (nodes[k].kind != k_empty) continue;
                const FaceSigns signs = face_signs(leaf, f, k, a, side);
                if ((signs.pos && signs.neg) || signs.near_zero) return true;
                continue;
            }
            for (std::uint32_t c = 0; c < 8; ++c)
                if (((c >> a) & 1u) == facing) stack.push_back(nodes[k].child + c);
        }
        return false;
    }

    /// Whether the subtree of node i holds a filled leaf.
    bool has_filled(std::uint32_t i) const {
        const pre::LargeVector<Node>& nodes = m_tree.nodes;
        std::vector<std::uint32_t> stack{i};
        while (!stack.empty()) {
            const std::uint32_t k = stack.back();
            stack.pop_back();
            if (nodes[k].child == 0) {
                if (is_filled(nodes[k].kind)) return true;
                continue;
            }
            for (std::uint32_t c = 0; c < 8; ++c) stack.push_back(nodes[k].child + c);
        }
        return false;
    }

    /// 2:1 balance around the new leaves (worklist: splits add more).
    void keep_balanced() {
        pre::LargeVector<Node>& nodes = m_tree.nodes;
        while (!m_work.empty()) {  // bounded: every iteration removes one entry; splits add finitely many
            const std::uint32_t leaf = m_work.back();
            m_work.pop_back();
            if (nodes[leaf].child != 0) continue;
            const std::uint32_t l = nodes[leaf].level;
            const std::int64_t top = std::int64_t{1} << l;
            // Coarser filled neighbours: the cells around at level l must lie in nodes of level >= l - 1.
            for (int d = 0; d < 27 && l >= 2; ++d) {
                if (d == 13) continue;
                const std::int64_t c[3] = {std::int64_t{nodes[leaf].x} + d % 3 - 1,
                                           std::int64_t{nodes[leaf].y} + (d / 3) % 3 - 1,
                                           std::int64_t{nodes[leaf].z} + d / 9 - 1};
                if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= top || c[1] >= top || c[2] >= top) continue;
                const std::uint32_t parent_cell[3] = {std::uint32_t(c[0] >> 1), std::uint32_t(c[1] >> 1),
                                                      std::uint32_t(c[2] >> 1)};
                for (;;) {  // bounded: each split goes one level down
                    const std::uint32_t node = m_tree.locate(parent_cell, l - 1);
                    if (nodes[node].child != 0 || nodes[node].level >= l - 1 || !is_filled(nodes[node].kind))
                        break;
                    split_all(node);
                }
            }
            // Finer filled neighbours: no filled leaf two levels finer may touch this one.
            if (l + 2 > m_max_level) continue;
            const std::int64_t top1 = std::int64_t{1} << (l + 1);
            bool split = false;
            for (int z = -1; z <= 2 && !split; ++z)
                for (int y = -1; y <= 2 && !split; ++y)
                    for (int x = -1; x <= 2 && !split; ++x) {
                        if (x >= 0 && x <= 1 && y >= 0 && y <= 1 && z >= 0 && z <= 1) continue;  // inside
                        const std::int64_t c[3] = {2 * std::int64_t{nodes[leaf].x} + x,
                                                   2 * std::int64_t{nodes[leaf].y} + y,
                                                   2 * std::int64_t{nodes[leaf].z} + z};
                        if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= top1 || c[1] >= top1 || c[2] >= top1)
                            continue;
                        const std::uint32_t cell[3] = {std::uint32_t(c[0]), std::uint32_t(c[1]),
                                                       std::uint32_t(c[2])};
                        const std::uint32_t node = m_tree.locate(cell, l + 1);
                        if (nodes[node].child != 0 && nodes[node].level == l + 1 && has_filled(node))
                            split = true;
                    }
            if (split) split_all(leaf);
        }
    }

    TreeBuilder& m_tree;
    std::uint32_t m_max_level;
    Near m_near;
    bool m_serial_only;
    std::vector<std::uint32_t> m_scratch;  ///< m_near's, on the serial path
    std::vector<std::uint32_t> m_added, m_work;
};

// ---- corners (thesis 4.2-4.3) ---------------------------------------------------------------------

struct CornerValue {
    double f = 0;
    float n[3] = {0, 0, 1};
    float color[3] = {255, 255, 255};
    bool supported = true;  ///< the corner's projection onto the local surface lies near data
};

/// Per-thread candidate buffer of the corner evaluation (structure of arrays).
struct Candidates {
    std::vector<double> px, py, pz, nx, ny, nz, sup2, inv2s2, wn, cr, cg, cb, data2;
    void clear() {
        for (auto* v : {&px, &py, &pz, &nx, &ny, &nz, &sup2, &inv2s2, &wn, &cr, &cg, &cb, &data2}) v->clear();
    }
    void add(const PointSet& ps, std::uint32_t id) {
        px.push_back(ps.pos[3 * id]);
        py.push_back(ps.pos[3 * id + 1]);
        pz.push_back(ps.pos[3 * id + 2]);
        nx.push_back(ps.nrm[3 * id]);
        ny.push_back(ps.nrm[3 * id + 1]);
        nz.push_back(ps.nrm[3 * id + 2]);
        sup2.push_back(ps.support[id] * ps.support[id]);
        inv2s2.push_back(ps.inv2s2[id]);
        wn.push_back(ps.wn[id]);
        cr.push_back(ps.col[3 * id]);
        cg.push_back(ps.col[3 * id + 1]);
        cb.push_back(ps.col[3 * id + 2]);
        data2.push_back(ps.data2.empty() ? 0.0 : ps.data2[id]);
    }
};

/// Weighted sums of eq. 4.2 around Q: positions relative to Q (short vectors: no cancellation).
struct Sums {
    double w = 0, px = 0, py = 0, pz = 0, nx = 0, ny = 0, nz = 0, r = 0, g = 0, b = 0;
    std::uint32_t count = 0;
    void add(double wi, double dx, double dy, double dz, double nxi, double nyi, double nzi, double ri,
             double gi, double bi) {
        w += wi;
        px += wi * dx, py += wi * dy, pz += wi * dz;
        nx += wi * nxi, ny += wi * nyi, nz += wi * nzi;
        r += wi * ri, g += wi * gi, b += wi * bi;
        ++count;
    }
};

/// eq. 4.3 from the sums: f = (Q - p) . n with p, n the weighted means (eq. 4.2); the stored
/// normal is n normalized.
CornerValue finish(const Sums& s) {
    CornerValue v;
    const double inv = 1.0 / s.w;
    const double qp[3] = {-s.px * inv, -s.py * inv, -s.pz * inv};  // Q - p
    const double n[3] = {s.nx * inv, s.ny * inv, s.nz * inv};
    v.f = qp[0] * n[0] + qp[1] * n[1] + qp[2] * n[2];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0 && std::isfinite(len)) {
        for (int a = 0; a < 3; ++a) v.n[a] = static_cast<float>(n[a] / len);
    } else {
        const double ql = std::sqrt(qp[0] * qp[0] + qp[1] * qp[1] + qp[2] * qp[2]);
        for (int a = 0; a < 3; ++a) v.n[a] = ql > 0 ? static_cast<float>(qp[a] / ql) : (a == 2 ? 1.0f : 0.0f);
    }
    v.color[0] = static_cast<float>(s.r * inv);
    v.color[1] = static_cast<float>(s.g * inv);
    v.color[2] = static_cast<float>(s.b * inv);
    return v;
}

/// Issue 15 (no surface where there is no data): the point where Q projects onto the plane the
/// corner value describes (p(Q) and n(Q) of eq. 4.2) must lie within data_reach x r_i of some
/// point i. Beyond the edge of a scan f extrapolates the last points' plane into a sheet, and
/// across a hole it spans the hole; this test stops both at about one radius of the data (a gap
/// wider than 2 data_reach r is not bridged). Only candidates (points whose support reaches the
/// corner's box) are tried: a corner farther than (support - data_reach) radii from its plane is
/// unsupported anyway.
/// `point(j, p, reach2)` gives candidate j's position and (data_reach r_j)^2, j < m.
template <class Point>
bool near_data(const Sums& s, const double q[3], std::size_t m, Point&& point) {
    const double inv = 1.0 / s.w;
    const double n[3] = {s.nx * inv, s.ny * inv, s.nz * inv};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-12) || !std::isfinite(len)) return false;       // normals cancel: no plane
    const double qp[3] = {-s.px * inv, -s.py * inv, -s.pz * inv};  // Q - p
    const double f = (qp[0] * n[0] + qp[1] * n[1] + qp[2] * n[2]) / len;
    // projection of Q onto the plane, relative to Q
    const double o[3] = {-f * n[0] / len, -f * n[1] / len, -f * n[2] / len};
    for (std::size_t j = 0; j < m; ++j) {
        double p[3], reach2;
        point(j, p, reach2);
        const double dx = q[0] + o[0] - p[0], dy = q[1] + o[1] - p[1], dz = q[2] + o[2] - p[2];
        if (dx * dx + dy * dy + dz * dz <= reach2) return true;
    }
    return false;
}

/// A corner no point's support reaches: eq. 4.1-4.3 over the points within d_min + support x
/// sigma_max (see iso_build.h), weights scaled by their largest value in log space. Such corners
/// are those of coarse leaves (level of detail, thesis 4.6) or far from the data; near_data
/// decides which over the same points: a coarse leaf's corner projects onto data, a corner
/// beyond the data's edge does not.
CornerValue evaluate_far(const InfluenceIndex& index, const PointSet& ps, const double q[3], double support,
                         double sigma_max, double start_radius, bool one_side,
                         std::vector<std::uint32_t>& ids, std::vector<double>& weights) {
    double radius = start_radius;
    double d_min2 = std::numeric_limits<double>::infinity();
    for (int round = 0; round < 80 && !std::isfinite(d_min2); ++round, radius *= 2) {
        ids.clear();
        gather_ball(index, ps, q, radius, ids);
        for (std::uint32_t id : ids) {
            const double* p = &ps.pos[3 * id];
            d_min2 = std::min(d_min2, (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                          (p[2] - q[2]) * (p[2] - q[2]));
        }
    }
    const double reach = std::sqrt(d_min2) + support * sigma_max;
    ids.clear();
    gather_ball(index, ps, q, reach, ids);
    double lmax = -std::numeric_limits<double>::infinity();
    auto log_weight = [&](std::uint32_t id) {
        const double* p = &ps.pos[3 * id];
        const double d2 =
            (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
        const double s = ps.sigma[id];
        return -d2 / (2 * s * s) - ps.log_sigma[id];  // log of eq. 4.1 up to the constant sqrt(2 pi)
    };
    // Each point's log weight, then its weight relative to the heaviest, once: the reach covers the
    // widest support, so most points lie many sigmas away and their weight underflows to exactly
    // 0, which std::exp reaches through a slow path; below -746 it is 0 without the call.
    weights.resize(ids.size());
    std::uint32_t heaviest = ids.empty() ? 0 : ids[0];
    for (std::size_t i = 0; i < ids.size(); ++i) {
        weights[i] = log_weight(ids[i]);
        if (weights[i] > lmax) lmax = weights[i], heaviest = ids[i];
    }
    for (double& w : weights) w = w - lmax < -746.0 ? 0.0 : std::exp(w - lmax);
    if (one_side) {  // as in CornerEvaluator::evaluate: the heavier side only
        const double* nb = &ps.nrm[3 * heaviest];
        auto same = [&](std::uint32_t id) {
            const double* n = &ps.nrm[3 * id];
            return n[0] * nb[0] + n[1] * nb[1] + n[2] * nb[2] >= 0;
        };
        double with = 0, against = 0;
        for (std::size_t i = 0; i < ids.size(); ++i) (same(ids[i]) ? with : against) += weights[i];
        const bool keep_same = with >= against;
        std::size_t kept = 0;
        for (std::size_t i = 0; i < ids.size(); ++i)
            if (same(ids[i]) == keep_same) ids[kept] = ids[i], weights[kept] = weights[i], ++kept;
        ids.resize(kept);
    }
    Sums sums;
    for (std::size_t i = 0; i < ids.size(); ++i) {
        const std::uint32_t id = ids[i];
        const double* p = &ps.pos[3 * id];
        const double* n = &ps.nrm[3 * id];
        sums.add(weights[i], p[0] - q[0], p[1] - q[1], p[2] - q[2], n[0], n[1], n[2], ps.col[3 * id],
                 ps.col[3 * id + 1], ps.col[3 * id + 2]);
    }
    CornerValue v = finish(sums);
    if (!ps.data2.empty())
        v.supported = near_data(sums, q, ids.size(), [&](std::size_t j, double p[3], double& reach2) {
            for (int a = 0; a < 3; ++a) p[a] = ps.pos[3 * ids[j] + a];
            reach2 = ps.data2[ids[j]];
        });
    return v;
}

/// Per-thread buffers of CornerEvaluator.
struct EvaluatorScratch {
    std::vector<std::uint32_t> ids, idx, far_ids;
    std::vector<double> far_weights;
    std::vector<double> d2, arg, w;
    Candidates cand;
    std::vector<std::size_t> far_corners;  ///< evaluate()'s corners beyond every support (indices into out)
    std::uint64_t counted = 0;             ///< points counted
    std::uint64_t unsupported = 0;         ///< corners whose projection lies away from the data
};

/// thesis 4.2-4.3: eq. 4.1-4.3 at corners, all inside one box, from one gather of the points whose
/// support reaches the box.
struct CornerEvaluator {
    const InfluenceIndex& index;
    const PointSet& ps;
    double support;       ///< in sigmas
    double sigma_max;     ///< largest sigma (far corners)
    double start_radius;  ///< first search radius for far corners
    bool one_side;        ///< BuildOptions::one_side

    /// The `count` corners at qs[3 k .. 3 k + 2], all within the closed box [blo, bhi], into out[k];
    /// a corner beyond every point's support is left to far() and its k appended to s.far_corners.
    void evaluate(const double* qs, std::size_t count, const double blo[3], const double bhi[3],
                  CornerValue* out, EvaluatorScratch& s) const {
        s.ids.clear();
        gather_overlapping(index, ps, ps.support, blo, bhi, s.ids);
        s.cand.clear();
        for (std::uint32_t id : s.ids) s.cand.add(ps, id);
        const Candidates& cand = s.cand;
        const std::size_t m = s.ids.size();
        if (s.d2.size() < m) s.d2.resize(m), s.idx.resize(m), s.arg.resize(m), s.w.resize(m);
        double* d2 = s.d2.data();
        double* arg = s.arg.data();
        double* w = s.w.data();
        std::uint32_t* idx = s.idx.data();
        for (std::size_t k = 0; k < count; ++k) {
            const double* q = qs + 3 * k;
            // Squared distances of every candidate (a branch-free, vectorized loop), then the
            // Gaussian weights (eq. 4.1) of those within their support, then the sums (eq. 4.2).
            for (std::size_t j = 0; j < m; ++j) {
                const double dx = cand.px[j] - q[0], dy = cand.py[j] - q[1], dz = cand.pz[j] - q[2];
                d2[j] = dx * dx + dy * dy + dz * dz;
            }
            std::size_t inside = 0;
            for (std::size_t j = 0; j < m; ++j) {
                idx[inside] = static_cast<std::uint32_t>(j);
                arg[inside] = -d2[j] * cand.inv2s2[j];
                inside += d2[j] <= cand.sup2[j];
            }
            // arg >= -support^2 / 2 >= -50: inside exp_nonpositive's domain
            for (std::size_t i = 0; i < inside; ++i) w[i] = detail::exp_nonpositive(arg[i]);
            if (one_side && inside > 1) {
                // The side of the surface Q belongs to: split the points by their normal against
                // the heaviest point's (more or less than 90 degrees away) and keep the side of
                // larger total weight; a lone point with a flipped normal does not win its corner.
                std::size_t best = 0;
                for (std::size_t i = 1; i < inside; ++i)
                    if (arg[i] > arg[best]) best = i;
                const std::uint32_t b = idx[best];
                double with = 0, against = 0;
                for (std::size_t i = 0; i < inside; ++i) {
                    const std::uint32_t j = idx[i];
                    const bool same =
                        cand.nx[j] * cand.nx[b] + cand.ny[j] * cand.ny[b] + cand.nz[j] * cand.nz[b] >= 0;
                    (same ? with : against) += cand.wn[j] * w[i];
                }
                const bool keep_same = with >= against;
                std::size_t kept = 0;
                for (std::size_t i = 0; i < inside; ++i) {
                    const std::uint32_t j = idx[i];
                    const bool same =
                        cand.nx[j] * cand.nx[b] + cand.ny[j] * cand.ny[b] + cand.nz[j] * cand.nz[b] >= 0;
                    if (same != keep_same) continue;
                    idx[kept] = j, w[kept] = w[i], ++kept;
                }
                inside = kept;
            }
            Sums sums;
            for (std::size_t i = 0; i < inside; ++i) {
                const std::uint32_t j = idx[i];
                sums.add(cand.wn[j] * w[i], cand.px[j] - q[0], cand.py[j] - q[1], cand.pz[j] - q[2],
                         cand.nx[j], cand.ny[j], cand.nz[j], cand.cr[j], cand.cg[j], cand.cb[j]);
            }
            if (sums.count > 0 && sums.w > 0) {
                out[k] = finish(sums);
                s.counted += sums.count;
                if (!ps.data2.empty()) {
                    out[k].supported = near_data(sums, q, m, [&](std::size_t j, double p[3], double& reach2) {
                        p[0] = cand.px[j], p[1] = cand.py[j], p[2] = cand.pz[j];
                        reach2 = cand.data2[j];
                    });
                    s.unsupported += !out[k].supported;
                }
            } else {
                s.far_corners.push_back(k);
            }
        }
    }

    /// The corner at q beyond every point's support (evaluate_far).
    CornerValue far(const double q[3], EvaluatorScratch& s) const {
        return evaluate_far(index, ps, q, support, sigma_max, start_radius, one_side, s.far_ids,
                            s.far_weights);
    }
};

std::int8_t quantize_value(double f, double scale) {
    // Sign-preserving: f > 0 never rounds to 0, so the quantized corners have the float corners'
    // signs and the two leaf arrays describe the same topology.
    const double q = std::round(f / scale * 127.0);
    if (f > 0) return static_cast<std::int8_t>(std::clamp(q, 1.0, 127.0));
    return static_cast<std::int8_t>(std::clamp(std::isfinite(q) ? q : 0.0, -127.0, 0.0));
}

std::int8_t quantize_unit(float v) {
    return static_cast<std::int8_t>(std::clamp(std::round(v * 127.0f), -127.0f, 127.0f));
}

std::uint8_t quantize_color(float v) {
    return static_cast<std::uint8_t>(std::clamp(std::round(v), 0.0f, 255.0f));
}

// ---- the build, step by step (iso_build.h lists the steps) ----------------------------------------

/// The radius source the input allows (checks the input's arrays against each other).
RadiusSource checked_radius_source(const BuildInput& in, const BuildOptions& o) {
    const std::size_t count = in.positions.size();
    if (in.normals.size() != count)
        throw Error("the ISO needs a normal per point (prt-import estimates them)");
    if (!in.radii.empty() && in.radii.size() != count) throw Error("radii and positions differ in count");
    if (!in.colors.empty() && in.colors.size() != count) throw Error("colors and positions differ in count");
    RadiusSource source = o.radius;
    if (source == RadiusSource::automatic)
        source = in.radii.empty() ? RadiusSource::knn : RadiusSource::radii;
    if (source == RadiusSource::radii && in.radii.empty())
        throw Error("no radii section: run prt-radii or use the k-NN radius (--radius knn)");
    return source;
}

/// The points the build uses (indices into the input) and their radii of influence r_i.
struct Influence {
    pre::LargeVector<std::uint32_t> keep;
    pre::LargeVector<double> radius;
};

double median_of(std::span<const double> values) {
    pre::LargeVector<double> v(values.begin(), values.end());
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
}

/// Step 1 (thesis 3.1): the usable points (finite position, non-zero normal, and a positive radius
/// when the radii come from the pool) and r_i: the pool's radii, or the k-NN distance with
/// prt-radii's global clamp (points with k coincident neighbours get 0 and are skipped, as
/// prt-octree skips them).
Influence radii_of_influence(const BuildInput& in, RadiusSource source, const BuildOptions& o,
                             unsigned threads, const Progress& progress, BuildStats& st) {
    const std::size_t count = in.positions.size();
    Influence inf;
    inf.keep.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        const pool::Float3 p = in.positions[i], n = in.normals[i];
        const double len = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !(len > 0) ||
            !std::isfinite(len))
            continue;
        if (source == RadiusSource::radii && !(in.radii[i] > 0.0f && std::isfinite(in.radii[i]))) continue;
        inf.keep.push_back(static_cast<std::uint32_t>(i));
    }
    inf.radius.resize(inf.keep.size());
    if (source == RadiusSource::radii) {
        for (std::size_t j = 0; j < inf.keep.size(); ++j) inf.radius[j] = in.radii[inf.keep[j]];
    } else if (!inf.keep.empty()) {
        std::vector<double> pos(3 * inf.keep.size());
        for (std::size_t j = 0; j < inf.keep.size(); ++j) {
            const pool::Float3 p = in.positions[inf.keep[j]];
            pos[3 * j] = p.x, pos[3 * j + 1] = p.y, pos[3 * j + 2] = p.z;
        }
        inf.radius = knn_distances(pos, o.knn, threads, progress);
        // prt-radii's outlier rule: radii above clamp x median become clamp x median.
        const double limit = o.knn_clamp > 0 ? o.knn_clamp * median_of(inf.radius) : 0.0;
        for (double& r : inf.radius)
            if (limit > 0 && r > limit) r = limit, ++st.radii_clamped;
        Influence usable;
        for (std::size_t j = 0; j < inf.keep.size(); ++j)
            if (inf.radius[j] > 0 && std::isfinite(inf.radius[j]))
                usable.keep.push_back(inf.keep[j]), usable.radius.push_back(inf.radius[j]);
        inf = std::move(usable);
    }
    st.skipped = count - inf.keep.size();
    if (inf.keep.empty()) throw Error("no usable point (positions, normals and radii all needed)");
    st.radius_median = median_of(inf.radius);
    return inf;
}

/// The root cube (thesis 4.3.1): every influence disk inside, its corner and edge in float (the
/// stored ones) and the same cube in double for the builder.
struct RootCube {
    float min[3];
    float size;
    Frame frame;
    double sigma_max;  ///< largest Gaussian sigma_i
};

RootCube root_cube(const BuildInput& in, const Influence& inf, const BuildOptions& o) {
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = std::numeric_limits<double>::infinity(), hi[a] = -lo[a];
    RootCube cube{};
    cube.sigma_max = 0;
    for (std::size_t j = 0; j < inf.keep.size(); ++j) {
        const pool::Float3 p = in.positions[inf.keep[j]];
        const double sigma = o.smoothing * inf.radius[j];
        const double rho = std::max(inf.radius[j], sigma);
        cube.sigma_max = std::max(cube.sigma_max, sigma);
        const double c[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a] - rho), hi[a] = std::max(hi[a], c[a] + rho);
    }
    double extent = 0;
    for (int a = 0; a < 3; ++a) extent = std::max(extent, hi[a] - lo[a]);
    cube.size = static_cast<float>(extent * 1.002);
    if (!(cube.size > 0.0f) || !std::isfinite(cube.size)) throw Error("the points span no volume");
    double corner[3];
    for (int a = 0; a < 3; ++a) {
        cube.min[a] = static_cast<float>(0.5 * (lo[a] + hi[a]) - 0.5 * double(cube.size));
        // float rounding must not leave a disk outside the cube
        while (double(cube.min[a]) > lo[a]) cube.min[a] = std::nextafter(cube.min[a], -INFINITY);
        while (double(cube.min[a]) + double(cube.size) < hi[a])
            cube.min[a] = std::nextafter(cube.min[a], INFINITY);
        corner[a] = cube.min[a];
    }
    cube.frame.set(corner, cube.size);
    return cube;
}

/// A 64-bit code and the index it sorts (plain data, for pre::Buffer and the radix sort).
struct KeyIndex {
    std::uint64_t key;
    std::uint32_t index;
};

/// The usable points with their Gaussians (eq. 4.1), sorted by their level-K code.
PointSet sorted_points(const BuildInput& in, const Influence& inf, const Frame& frame, const BuildOptions& o,
                       unsigned threads) {
    const std::size_t n = inf.keep.size();
    PointSet ps;
    ps.n = n;
    pre::Buffer<KeyIndex> order(n);  // first touched by the parallel fill
    parallel_chunks(n, 1 << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t j = b; j < e; ++j) {
            const pool::Float3 p = in.positions[inf.keep[j]];
            order[j] = {morton3(frame.cell(p.x, 0, k_code_level), frame.cell(p.y, 1, k_code_level),
                                frame.cell(p.z, 2, k_code_level)),
                        static_cast<std::uint32_t>(j)};
        }
    });
    pre::radix_sort_by(order, 64, threads, [](const KeyIndex& e) { return e.key; });  // stable: by (code, j)
    using Doubles = pre::Buffer<double>;
    ps.pos = Doubles(3 * n), ps.nrm = Doubles(3 * n), ps.col = pre::Buffer<std::uint8_t>(3 * n);
    ps.sigma = Doubles(n), ps.support = Doubles(n), ps.rho = Doubles(n), ps.reach = Doubles(n);
    ps.inv2s2 = Doubles(n), ps.wn = Doubles(n), ps.log_sigma = Doubles(n);
    ps.code = pre::Buffer<std::uint64_t>(n);
    if (o.data_reach > 0) ps.data2 = Doubles(n);
    parallel_chunks(n, 1 << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t j = order[i].index;
            const std::uint32_t src = inf.keep[j];
            const double r = inf.radius[j];
            const pool::Float3 p = in.positions[src], nv = in.normals[src];
            const double len = std::sqrt(double(nv.x) * nv.x + double(nv.y) * nv.y + double(nv.z) * nv.z);
            ps.pos[3 * i] = p.x, ps.pos[3 * i + 1] = p.y, ps.pos[3 * i + 2] = p.z;
            ps.nrm[3 * i] = nv.x / len, ps.nrm[3 * i + 1] = nv.y / len, ps.nrm[3 * i + 2] = nv.z / len;
            const pool::Rgba8 c = in.colors.empty() ? pool::Rgba8{255, 255, 255, 255} : in.colors[src];
            ps.col[3 * i] = c.r, ps.col[3 * i + 1] = c.g, ps.col[3 * i + 2] = c.b;
            ps.sigma[i] = o.smoothing * r;
            const double s = ps.sigma[i];
            ps.inv2s2[i] = 1.0 / (2.0 * s * s);
            ps.wn[i] = 1.0 / std::sqrt(2.0 * std::numbers::pi * s * s);
            ps.log_sigma[i] = std::log(s);
            ps.support[i] = o.support * ps.sigma[i];
            ps.rho[i] = std::max(r, ps.sigma[i]);
            ps.reach[i] = std::max(ps.support[i], ps.rho[i]);
            if (o.data_reach > 0) ps.data2[i] = (o.data_reach * r) * (o.data_reach * r);
            ps.code[i] = order[i].key;
        }
    });
    return ps;
}

/// The corner values of the evaluated leaves: each owns 8 corner slots, which slot_corner maps into
/// `values` (a corner shared by several leaves is one value).
struct CornerTable {
    pre::LargeVector<CornerValue> values;
    pre::LargeVector<std::uint32_t> slot_corner;
    pre::LargeVector<std::uint32_t> leaf_slot;  ///< node -> its evaluated leaf (UINT32_MAX: never evaluated)
    pre::LargeVector<std::uint64_t> keys;       ///< sorted codes of values[0, keys.size()): step 5's corners
    std::unordered_map<std::uint64_t, std::uint32_t> added;  ///< code -> value: the closure's corners

    /// The value index of the corner with code `key`, or UINT32_MAX when not evaluated yet.
    std::uint32_t find(std::uint64_t key) const {
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        if (it != keys.end() && *it == key) return static_cast<std::uint32_t>(it - keys.begin());
        const auto a = added.find(key);
        return a != added.end() ? a->second : UINT32_MAX;
    }

    const CornerValue& at(std::uint32_t node, std::uint32_t c) const {
        return values[slot_corner[8 * leaf_slot[node] + c]];
    }
    /// Bit c: corner c has f > 0. A leaf with a corner away from the data (step 5c) holds no
    /// surface: its mask is 0, so the closure does not grow from it and step 6 empties it.
    std::uint32_t sign_mask(std::uint32_t node) const {
        std::uint32_t m = 0;
        for (std::uint32_t c = 0; c < 8; ++c) {
            const CornerValue& v = at(node, c);
            if (!v.supported) return 0u;
            m |= (v.f > 0 ? 1u : 0u) << c;
        }
        return m;
    }
    bool unsupported(std::uint32_t node) const {
        for (std::uint32_t c = 0; c < 8; ++c)
            if (!at(node, c).supported) return true;
        return false;
    }
};

/// The filled leaves (active and passive, counted in `st`), in node order.
std::vector<std::uint32_t> filled_leaves(const pre::LargeVector<Node>& nodes, unsigned threads,
                                         BuildStats& st) {
    std::vector<std::uint32_t> filled(nodes.size());
    filled.resize(parallel_select(
        nodes.size(), threads, [&](std::size_t i) { return nodes[i].child == 0 && is_filled(nodes[i].kind); },
        [&](std::size_t rank, std::size_t i) { filled[rank] = static_cast<std::uint32_t>(i); }));
    filled.shrink_to_fit();  // kept for the whole build: not the node count's room
    std::atomic<std::uint64_t> active{0};
    parallel_chunks(filled.size(), 1 << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::uint64_t n = 0;
        for (std::size_t k = b; k < e; ++k) n += nodes[filled[k]].kind == k_active;
        active += n;
    });
    st.active_leaves += active.load();
    st.passive_leaves += filled.size() - active.load();
    return filled;
}

/// The code of corner c of a node (its cell's corner at the finest code level).
std::uint64_t corner_key(const Node& nd, std::uint32_t c) {
    const std::uint32_t s = k_code_level - nd.level;
    return morton3((nd.x + (c & 1u)) << s, (nd.y + ((c >> 1) & 1u)) << s, (nd.z + ((c >> 2) & 1u)) << s);
}

/// Counts of BlockEvaluation::run, for BuildStats.
struct CornerCounts {
    std::uint64_t far = 0, counted = 0, unsupported = 0;
};

/// Evaluates corners given by sorted distinct codes in blocks sharing a node at a level at least
/// as wide as the median support (`median_support`): one gather of candidates per block. Blocks
/// half as wide held 4.3 corners each on the 1M room and the gathers (3 per corner's worth of
/// node searches and 28 points scanned per corner) took more than the sums; at this width a block
/// holds 22 corners, and step 5 took 1.8 s instead of 3.0 s (2 threads; four times wider: 1.9 s). f, n
/// and the color depend on the corner's position only (the candidates within its support, in the
/// index's order, whatever the block's box); the step-5c flag `supported` looks at every gathered
/// candidate, so it may depend on the box. Each corner is evaluated once (step 5 and the closure's
/// rounds share CornerTable's values), so the leaves that share a corner agree on it.
struct BlockEvaluation {
    const CornerEvaluator& evaluator;
    const Frame& frame;
    double median_support;

    CornerCounts run(std::span<const std::uint64_t> keys, CornerValue* out, unsigned threads,
                     const Progress& progress) const {
        if (keys.empty()) return {};
        const std::uint32_t block_level = detail::level_for_extent(frame, median_support, 1.0, k_code_level);
        const std::uint32_t block_shift = 3 * (k_code_level - block_level);
        std::vector<std::size_t> blocks(keys.size() + 1);  // where each block's keys start
        blocks.resize(parallel_select(
            keys.size(), threads,
            [&](std::size_t i) { return i == 0 || (keys[i] >> block_shift) != (keys[i - 1] >> block_shift); },
            [&](std::size_t rank, std::size_t i) { blocks[rank] = i; }));
        blocks.push_back(keys.size());
        std::atomic<std::uint64_t> corners_done{0}, counted{0}, unsupported{0};
        const double corner_step = frame.edge(k_code_level);
        std::vector<std::size_t> far_keys;  // corners beyond every support: evaluated after the blocks
        std::mutex far_mutex;
        parallel_chunks(blocks.size() - 1, 16, threads, [&](std::size_t b0, std::size_t b1, unsigned worker) {
            EvaluatorScratch scratch;
            std::vector<double> qs;
            for (std::size_t bi = b0; bi < b1; ++bi) {
                const std::size_t first = blocks[bi], last = blocks[bi + 1];
                const std::uint64_t prefix = keys[first] >> block_shift;
                double blo[3], bhi[3];
                frame.box(block_level, pre::compact_bits21(prefix), pre::compact_bits21(prefix >> 1),
                          pre::compact_bits21(prefix >> 2), blo, bhi);
                qs.clear();
                for (std::size_t ci = first; ci < last; ++ci) {
                    const std::uint64_t key = keys[ci];
                    qs.push_back(frame.lo[0] + corner_step * pre::compact_bits21(key));
                    qs.push_back(frame.lo[1] + corner_step * pre::compact_bits21(key >> 1));
                    qs.push_back(frame.lo[2] + corner_step * pre::compact_bits21(key >> 2));
                }
                scratch.far_corners.clear();
                evaluator.evaluate(qs.data(), last - first, blo, bhi, out + first, scratch);
                if (!scratch.far_corners.empty()) {
                    const std::lock_guard<std::mutex> lock(far_mutex);
                    for (const std::size_t k : scratch.far_corners) far_keys.push_back(first + k);
                }
                const std::uint64_t d = corners_done.fetch_add(last - first) + (last - first);
                if (worker == 0 && progress) progress("corners", d, keys.size());
            }
            counted += scratch.counted;
            unsupported += scratch.unsupported;
        });
        // Far corners cost one growing ball search each (tens of times a block's corner) and gather
        // in a few blocks, mostly the closure's: one at a time they leave the other workers idle.
        // A far corner's value depends on its position alone, so the order does not matter. One
        // corner a chunk: their costs differ by orders of magnitude (the ball grows until it meets
        // a point), so larger chunks left a worker with the expensive ones while the others waited.
        std::vector<EvaluatorScratch> per_worker(std::max(threads, 1u));
        parallel_chunks(far_keys.size(), 1, threads, [&](std::size_t b, std::size_t e, unsigned worker) {
            EvaluatorScratch& scratch = per_worker[worker];
            for (std::size_t i = b; i < e; ++i) {
                const std::uint64_t key = keys[far_keys[i]];
                const double q[3] = {frame.lo[0] + corner_step * pre::compact_bits21(key),
                                     frame.lo[1] + corner_step * pre::compact_bits21(key >> 1),
                                     frame.lo[2] + corner_step * pre::compact_bits21(key >> 2)};
                CornerValue& v = out[far_keys[i]];
                v = evaluator.far(q, scratch);
                if (!v.supported) ++unsupported;
            }
        });
        return CornerCounts{far_keys.size(), counted.load(), unsupported.load()};
    }
};

/// Step 5 (thesis 4.2-4.3, eq. 4.1-4.3): f(Q), n(Q) and the color at every distinct corner of the
/// `filled` leaves, sorted by code (BlockEvaluation).
CornerTable evaluate_corners(const pre::LargeVector<Node>& nodes, const std::vector<std::uint32_t>& filled,
                             const BlockEvaluation& blocks, unsigned threads, const Progress& progress,
                             BuildStats& st) {
    CornerTable table;
    // The tables' pages are touched in parallel first (buffer.h, prefault); the closure (step 5b)
    // grows them a leaf at a time, into the room reserved here.
    pre::resize_prefaulted(table.leaf_slot, nodes.size(), threads, nodes.size() + nodes.size() / 4);
    fill_parallel(table.leaf_slot, UINT32_MAX, threads);
    parallel_chunks(filled.size(), 1 << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t f = b; f < e; ++f) table.leaf_slot[filled[f]] = static_cast<std::uint32_t>(f);
    });
    pre::Buffer<KeyIndex> slots(8 * filled.size());  // first touched by the parallel fill
    parallel_chunks(filled.size(), 1 << 14, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t f = b; f < e; ++f)
            for (std::uint32_t c = 0; c < 8; ++c)
                slots[8 * f + c] = {corner_key(nodes[filled[f]], c), static_cast<std::uint32_t>(8 * f + c)};
    });
    pre::radix_sort_by(slots, 64, threads, [](const KeyIndex& e) { return e.key; });
    // The distinct codes and each slot's corner, in two parallel passes over fixed chunks: count
    // the distinct codes of each chunk, then (after a prefix sum) write them and the slots' ranks.
    const std::size_t m = slots.size();
    constexpr std::size_t k_chunk = std::size_t{1} << 15;
    const std::size_t chunks = (m + k_chunk - 1) / k_chunk;
    auto starts_corner = [&](std::size_t i) { return i == 0 || slots[i].key != slots[i - 1].key; };
    std::vector<std::size_t> before(chunks + 1, 0);  // distinct codes before each chunk
    parallel_chunks(m, k_chunk, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::size_t count = 0;
        for (std::size_t i = b; i < e; ++i) count += starts_corner(i) ? 1 : 0;
        before[b / k_chunk + 1] = count;
    });
    for (std::size_t c = 0; c < chunks; ++c) before[c + 1] += before[c];
    pre::LargeVector<std::uint64_t>& corner_keys = table.keys;
    pre::resize_prefaulted(corner_keys, before[chunks], threads);
    pre::resize_prefaulted(table.slot_corner, m, threads, m + m / 4);
    parallel_chunks(m, k_chunk, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::size_t rank = before[b / k_chunk];  // corners started before slot i (i included, below)
        for (std::size_t i = b; i < e; ++i) {
            if (starts_corner(i)) corner_keys[rank++] = slots[i].key;
            table.slot_corner[slots[i].index] = static_cast<std::uint32_t>(rank - 1);
        }
    });
    pre::Buffer<KeyIndex>().swap(slots);
    pre::resize_prefaulted(table.values, corner_keys.size(), threads,
                           corner_keys.size() + corner_keys.size() / 4);
    const CornerCounts n = blocks.run(corner_keys, table.values.data(), threads, progress);
    st.far_corners = n.far;
    st.unsupported_corners = n.unsupported;
    st.mean_neighbours_x100 =
        corner_keys.size() > st.far_corners ? 100 * n.counted / (corner_keys.size() - st.far_corners) : 0;
    st.corners = corner_keys.size();
    return table;
}

/// Step 5b (with 5c's support): the surface closure, from the `frontier` of evaluated leaves
/// until no face leads to a new leaf; the new leaves' corners are evaluated into `table`.
void close_surface(TreeBuilder& tree, CornerTable& table, std::vector<std::uint32_t> frontier,
                   const BlockEvaluation& blocks, const BuildOptions& o, unsigned threads, BuildStats& st) {
    const CornerEvaluator& evaluator = blocks.evaluator;
    const Frame& frame = blocks.frame;
    pre::LargeVector<Node>& nodes = tree.nodes;
    pre::reserve_prefaulted(nodes, nodes.size() + nodes.size() / 4, threads);  // its splits: no copy here
    SurfaceClosure closure(
        tree, o.max_level,
        [&](std::uint32_t level, std::uint32_t x, std::uint32_t y, std::uint32_t z,
            std::vector<std::uint32_t>& near_ids) {
            double blo[3], bhi[3];
            frame.box(level, x, y, z, blo, bhi);
            near_ids.clear();
            gather_overlapping(evaluator.index, evaluator.ps, evaluator.ps.support, blo, bhi, near_ids);
            return !near_ids.empty();
        },
        o.closure_serial_only);
    for (std::uint32_t round = 0; round < 256 && !frontier.empty(); ++round) {  // every round adds leaves
        std::vector<std::uint32_t> added = closure.close(
            frontier, table.leaf_slot, [&](std::uint32_t node) { return table.sign_mask(node); },
            [&](std::uint32_t node, double f[8]) {
                for (std::uint32_t c = 0; c < 8; ++c) f[c] = table.at(node, c).f;
            },
            threads);
        st.closure_leaves += added.size();
        // New leaves: their corners not evaluated yet (most are shared with the leaves they grew
        // from or with each other), in blocks as in step 5.
        const std::size_t base = table.slot_corner.size() / 8;
        table.leaf_slot.resize(nodes.size(), UINT32_MAX);
        for (std::size_t k = 0; k < added.size(); ++k)
            table.leaf_slot[added[k]] = static_cast<std::uint32_t>(base + k);
        table.slot_corner.resize(table.slot_corner.size() + 8 * added.size());
        std::uint32_t* slots = table.slot_corner.data() + 8 * base;
        std::vector<std::uint64_t> fresh;
        for (std::size_t k = 0; k < added.size(); ++k)
            for (std::uint32_t c = 0; c < 8; ++c) {
                const std::uint64_t key = corner_key(nodes[added[k]], c);
                slots[8 * k + c] = table.find(key);
                if (slots[8 * k + c] == UINT32_MAX) fresh.push_back(key);
            }
        std::sort(fresh.begin(), fresh.end());
        fresh.erase(std::unique(fresh.begin(), fresh.end()), fresh.end());
        const std::size_t corner_base = table.values.size();
        table.values.resize(corner_base + fresh.size());
        const CornerCounts n = blocks.run(fresh, table.values.data() + corner_base, threads, nullptr);
        for (std::size_t i = 0; i < fresh.size(); ++i)
            table.added.emplace(fresh[i], static_cast<std::uint32_t>(corner_base + i));
        for (std::size_t k = 0; k < added.size(); ++k)
            for (std::uint32_t c = 0; c < 8; ++c)
                if (slots[8 * k + c] == UINT32_MAX)
                    slots[8 * k + c] = table.added.at(corner_key(nodes[added[k]], c));
        st.far_corners += n.far;
        st.unsupported_corners += n.unsupported;
        st.corner_slots += 8 * added.size();
        frontier.swap(added);
    }
}

/// The tree cut for steps 6 and 7's passes over whole subtrees: `items`, in depth-first order, the
/// nodes at level k_cut_level and the leaves above it; `above`, in pre-order, the internal nodes
/// above that level (levels 0-2: at most 73 nodes). Each item's subtree is walked by one worker.
struct TreeCut {
    static constexpr std::uint32_t k_cut_level = 3;
    std::vector<std::uint32_t> items, above;
};

TreeCut cut_tree(const pre::LargeVector<Node>& nodes) {
    TreeCut cut;
    std::vector<std::uint32_t> stack{0};
    while (!stack.empty()) {  // bounded by the nodes above the cut
        const std::uint32_t i = stack.back();
        stack.pop_back();
        if (nodes[i].child == 0 || nodes[i].level >= TreeCut::k_cut_level) {
            cut.items.push_back(i);
            continue;
        }
        cut.above.push_back(i);
        for (std::uint32_t c = 8; c-- > 0;) stack.push_back(nodes[i].child + c);
    }
    return cut;
}

/// Step 6: which nodes survive: filled leaves whose corners change sign (and, unless
/// drop_uncrossed, those without a change that are not unsupported), and their ancestors.
std::vector<std::uint8_t> crossed_leaves(const pre::LargeVector<Node>& nodes, const TreeCut& cut,
                                         const CornerTable& table, const BuildOptions& o, unsigned threads,
                                         BuildStats& st) {
    std::vector<std::uint8_t> keep_node(nodes.size(), 0);
    std::atomic<std::uint64_t> slots{0}, unsupported{0}, uncrossed{0};
    parallel_chunks(nodes.size(), 1 << 14, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::uint64_t n_slots = 0, n_unsupported = 0, n_uncrossed = 0;
        for (std::size_t i = b; i < e; ++i) {
            if (nodes[i].child != 0 || !is_filled(nodes[i].kind)) continue;
            n_slots += 8;
            const std::uint32_t m = table.sign_mask(static_cast<std::uint32_t>(i));
            if (m != 0 && m != 0xffu) {
                keep_node[i] = 1;
            } else if (table.unsupported(static_cast<std::uint32_t>(i))) {
                ++n_unsupported;
            } else {
                ++n_uncrossed;
                if (!o.drop_uncrossed) keep_node[i] = 1;
            }
        }
        slots += n_slots, unsupported += n_unsupported, uncrossed += n_uncrossed;
    });
    st.corner_slots = slots.load();
    st.unsupported_leaves += unsupported.load();
    st.uncrossed_leaves += uncrossed.load();
    // An internal node survives when a child does: each cut subtree in parallel (children come
    // after their parent, so its nodes in reverse pre-order), then the nodes above the cut.
    parallel_chunks(cut.items.size(), 1, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::vector<std::uint32_t> order, stack;
        for (std::size_t k = b; k < e; ++k) {
            order.clear();
            stack.assign(1, cut.items[k]);
            while (!stack.empty()) {  // bounded by the subtree
                const std::uint32_t i = stack.back();
                stack.pop_back();
                if (nodes[i].child == 0) continue;
                order.push_back(i);
                for (std::uint32_t c = 0; c < 8; ++c) stack.push_back(nodes[i].child + c);
            }
            for (std::size_t j = order.size(); j-- > 0;) {
                const std::uint32_t i = order[j];
                for (std::uint32_t c = 0; c < 8; ++c) keep_node[i] |= keep_node[nodes[i].child + c];
            }
        }
    });
    for (std::size_t j = cut.above.size(); j-- > 0;) {
        const std::uint32_t i = cut.above[j];
        for (std::uint32_t c = 0; c < 8; ++c) keep_node[i] |= keep_node[nodes[i].child + c];
    }
    return keep_node;
}

/// The kept leaves in depth-first (Morton) order; leaf_of[node] is a leaf's index among them.
/// Each cut item's leaves are listed by one worker, then placed after the items before it.
std::vector<std::uint32_t> depth_first_leaves(const pre::LargeVector<Node>& nodes, const TreeCut& cut,
                                              const std::vector<std::uint8_t>& keep_node,
                                              std::vector<std::uint32_t>& leaf_of, unsigned threads) {
    std::vector<std::vector<std::uint32_t>> item_leaves(cut.items.size());
    parallel_chunks(cut.items.size(), 1, threads, [&](std::size_t b, std::size_t e, unsigned) {
        std::vector<std::uint32_t> stack;
        for (std::size_t k = b; k < e; ++k) {
            stack.assign(1, cut.items[k]);
            while (!stack.empty()) {  // bounded by the subtree
                const std::uint32_t i = stack.back();
                stack.pop_back();
                if (!keep_node[i]) continue;
                if (nodes[i].child == 0) {
                    item_leaves[k].push_back(i);
                    continue;
                }
                for (std::uint32_t c = 8; c-- > 0;) stack.push_back(nodes[i].child + c);
            }
        }
    });
    std::vector<std::size_t> first(cut.items.size() + 1, 0);
    for (std::size_t k = 0; k < cut.items.size(); ++k) first[k + 1] = first[k] + item_leaves[k].size();
    std::vector<std::uint32_t> dfs_leaves(first.back());
    leaf_of.resize(nodes.size());
    fill_parallel(leaf_of, UINT32_MAX, threads);
    parallel_chunks(cut.items.size(), 1, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t k = b; k < e; ++k)
            for (std::size_t j = 0; j < item_leaves[k].size(); ++j) {
                const std::uint32_t leaf = static_cast<std::uint32_t>(first[k] + j);
                dfs_leaves[leaf] = item_leaves[k][j];
                leaf_of[item_leaves[k][j]] = leaf;
            }
    });
    return dfs_leaves;
}

/// Step 7 (thesis 4.4): the leaf arrays, quantized (56 bytes per leaf) and/or in floats.
void encode_leaves(const pre::LargeVector<Node>& nodes, const std::vector<std::uint32_t>& dfs_leaves,
                   const CornerTable& table, const Frame& frame, const BuildOptions& o, bool colors,
                   unsigned threads, IsoModel& model) {
    const bool q8 = o.storage != Storage::f32, f32 = o.storage != Storage::q8;
    // IsoModel's vectors zero their elements on this thread, on huge pages the workers touched
    // first (buffer.h, prefault).
    if (q8) pre::resize_on_huge_pages(model.leaves_q8, dfs_leaves.size(), threads);
    if (f32) pre::resize_on_huge_pages(model.leaves_f32, dfs_leaves.size(), threads);
    parallel_chunks(dfs_leaves.size(), 1 << 14, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t li = b; li < e; ++li) {
            const Node& nd = nodes[dfs_leaves[li]];
            const double scale = pool::k_iso_q8_range * frame.edge(nd.level);
            for (std::uint32_t c = 0; c < 8; ++c) {
                const CornerValue& v = table.at(dfs_leaves[li], c);
                if (q8) {
                    pool::IsoLeafQ8& q = model.leaves_q8[li];
                    q.value[c] = quantize_value(v.f, scale);
                    for (int a = 0; a < 3; ++a) {
                        q.normal[c][a] = quantize_unit(v.n[a]);
                        q.color[c][a] = colors ? quantize_color(v.color[a]) : 255;
                    }
                }
                if (f32) {
                    pool::IsoLeafF32& l = model.leaves_f32[li];
                    l.value[c] = static_cast<float>(v.f);
                    for (int a = 0; a < 3; ++a) l.normal[c][a] = v.n[a];
                    l.color[c] = colors ? pool::Rgba8{quantize_color(v.color[0]), quantize_color(v.color[1]),
                                                      quantize_color(v.color[2]), 255}
                                        : pool::Rgba8{255, 255, 255, 255};
                }
            }
        }
    });
}

/// Step 7: the node pool, breadth first; subtrees without a filled leaf become one empty leaf.
void encode_nodes(const pre::LargeVector<Node>& nodes, const std::vector<std::uint8_t>& keep_node,
                  const std::vector<std::uint32_t>& leaf_of, unsigned threads, IsoModel& model) {
    // Level by level (a node's level is its depth): the words of one level in parallel, an internal
    // node's children at the queue's end plus 8 x the internal nodes before it in its level (a
    // prefix count, parallel_select), so the words are those of a serial breadth-first queue.
    BuildStats& st = model.stats;
    std::vector<std::uint32_t>& words = model.nodes;
    words.clear();
    std::vector<std::uint32_t> level{0}, inner, next;
    std::size_t queued = 1;   // entries of the queue so far: this level's and those before
    while (!level.empty()) {  // bounded by the tree's depth
        const std::size_t base = words.size();
        words.resize(base + level.size());
        inner.resize(level.size());
        const std::size_t n_inner = parallel_select(
            level.size(), threads,
            [&](std::size_t k) { return nodes[level[k]].child != 0 && keep_node[level[k]]; },
            [&](std::size_t rank, std::size_t k) {
                inner[rank] = level[k];
                words[base + k] =
                    pool::make_node(pool::NodeType::internal, static_cast<std::uint32_t>(queued + 8 * rank));
            });
        if (n_inner > 0 && queued + 8 * n_inner > pool::k_node_address_max)
            throw Error("the ISO octree needs more than 2^30 nodes (lower --max-level)");
        std::atomic<std::uint64_t> leaves{0};
        parallel_chunks(level.size(), 1 << 14, threads, [&](std::size_t b, std::size_t e, unsigned) {
            std::uint64_t n_leaves = 0;
            for (std::size_t k = b; k < e; ++k) {
                const std::uint32_t i = level[k];
                if (nodes[i].child != 0 && keep_node[i]) continue;  // internal: written above
                if (nodes[i].child == 0 && keep_node[i]) {
                    words[base + k] = pool::make_node(pool::NodeType::filled_leaf, leaf_of[i]);
                    ++n_leaves;
                } else {
                    words[base + k] = pool::make_node(pool::NodeType::empty_leaf, 0);
                }
            }
            leaves += n_leaves;
        });
        if (leaves.load() > 0) {
            const std::uint32_t l = nodes[level[0]].level;
            st.depth = std::max<std::uint32_t>(st.depth, l);
            st.leaves_per_level[l] += leaves.load();
        }
        next.resize(8 * n_inner);
        parallel_chunks(n_inner, 1 << 12, threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t r = b; r < e; ++r)
                for (std::uint32_t c = 0; c < 8; ++c) next[8 * r + c] = nodes[inner[r]].child + c;
        });
        queued += next.size();
        level.swap(next);
    }
}

/// The IsoInfo record of the finished model.
void fill_info(IsoModel& model, const RootCube& cube, const BuildOptions& o, bool colors,
               RadiusSource source) {
    const BuildStats& st = model.stats;
    const bool q8 = o.storage != Storage::f32, f32 = o.storage != Storage::q8;
    pool::IsoInfo& info = model.info;
    for (int a = 0; a < 3; ++a) info.root_min[a] = cube.min[a];
    info.root_size = cube.size;
    info.node_count = static_cast<std::uint32_t>(model.nodes.size());
    info.leaf_count = static_cast<std::uint32_t>(st.leaves);
    info.min_level = o.min_level;
    info.max_level = o.max_level;
    info.depth = st.depth;
    info.flags = (q8 ? pool::k_iso_has_q8 : 0u) | (f32 ? pool::k_iso_has_f32 : 0u) |
                 (colors ? pool::k_iso_colors : 0u) | (o.balance ? pool::k_iso_balanced : 0u) |
                 (source == RadiusSource::knn ? pool::k_iso_radii_knn : 0u);
    info.smoothing = o.smoothing;
    info.support = o.support;
    info.active_leaves = static_cast<std::uint32_t>(st.active_leaves);
    info.passive_leaves = static_cast<std::uint32_t>(st.passive_leaves);
    info.corner_count = static_cast<std::uint32_t>(std::min<std::uint64_t>(st.corners, UINT32_MAX));
}

}  // namespace

IsoModel build_iso(const BuildInput& in, const BuildOptions& o, const Progress& progress) {
    validate(o);
    const auto t_start = Clock::now();
    const unsigned threads = resolve_threads(o.threads);
    const RadiusSource source = checked_radius_source(in, o);
    IsoModel model;
    BuildStats& st = model.stats;
    st.points = in.positions.size();

    auto t0 = Clock::now();
    const Influence influence = radii_of_influence(in, source, o, threads, progress, st);  // step 1
    st.seconds_radii = seconds_since(t0);

    t0 = Clock::now();
    const RootCube cube = root_cube(in, influence, o);
    const PointSet ps = sorted_points(in, influence, cube.frame, o, threads);
    const InfluenceIndex index = build_index(ps, cube.frame, threads);
    TreeBuilder tree(ps, index, cube.frame, o);
    tree.build_from_points(threads);  // step 2
    st.seconds_tree = seconds_since(t0);

    t0 = Clock::now();
    if (o.passive) {  // step 3
        tree.mark_passive(threads, progress);
        st.min_level_splits = tree.enforce_min_level();
    }
    st.seconds_passive = seconds_since(t0);

    t0 = Clock::now();
    if (o.balance) st.balance_splits = tree.balance(threads, progress);  // step 4
    st.seconds_balance = seconds_since(t0);

    t0 = Clock::now();
    const pre::LargeVector<Node>& nodes = tree.nodes;
    const double median_support = median_of({ps.support.begin(), ps.support.end()});
    const CornerEvaluator evaluator{index, ps, o.support, cube.sigma_max, 2 * median_support, o.one_side};
    const std::vector<std::uint32_t> filled = filled_leaves(nodes, threads, st);
    const BlockEvaluation blocks{evaluator, cube.frame, median_support};
    CornerTable table = evaluate_corners(nodes, filled, blocks, threads, progress, st);
    st.seconds_corners = seconds_since(t0);

    t0 = Clock::now();
    if (o.closure) close_surface(tree, table, filled, blocks, o, threads, st);  // steps 5b, 5c
    st.seconds_closure = seconds_since(t0);

    t0 = Clock::now();
    const TreeCut cut = cut_tree(nodes);
    const std::vector<std::uint8_t> keep_node = crossed_leaves(nodes, cut, table, o, threads, st);  // step 6
    std::vector<std::uint32_t> leaf_of;
    const std::vector<std::uint32_t> dfs_leaves = depth_first_leaves(nodes, cut, keep_node, leaf_of, threads);
    const bool colors = !in.colors.empty();
    encode_leaves(nodes, dfs_leaves, table, cube.frame, o, colors, threads, model);  // step 7
    encode_nodes(nodes, keep_node, leaf_of, threads, model);
    st.leaves = dfs_leaves.size();
    st.nodes = model.nodes.size();
    st.seconds_encode = seconds_since(t0);

    fill_info(model, cube, o, colors, source);
    st.bytes = sizeof(pool::IsoInfo) + 4 * model.nodes.size() +
               sizeof(pool::IsoLeafQ8) * model.leaves_q8.size() +
               sizeof(pool::IsoLeafF32) * model.leaves_f32.size();
    st.seconds_total = seconds_since(t_start);
    return model;
}

std::vector<LeafCell> leaf_cells(std::span<const std::uint32_t> nodes, std::uint32_t leaf_count) {
    std::vector<LeafCell> cells(leaf_count);
    if (nodes.empty()) return cells;
    std::vector<std::pair<std::uint32_t, LeafCell>> queue{{0, LeafCell{}}};
    for (std::size_t k = 0; k < queue.size(); ++k) {
        const auto [i, cell] = queue[k];
        const std::uint32_t w = nodes[i];
        const pool::NodeType type = pool::node_type(w);
        const std::uint32_t a = pool::node_address(w);
        if (type == pool::NodeType::internal) {
            for (std::uint32_t c = 0; c < 8; ++c)
                queue.push_back(
                    {a + c, LeafCell{cell.level + 1, 2 * cell.x + (c & 1u), 2 * cell.y + ((c >> 1) & 1u),
                                     2 * cell.z + ((c >> 2) & 1u)}});
        } else if (type == pool::NodeType::filled_leaf && a < leaf_count) {
            cells[a] = cell;
        }
    }
    return cells;
}

void corner_position(const pool::IsoInfo& info, const LeafCell& cell, int corner, double q[3]) {
    const double e = std::ldexp(double(info.root_size), -static_cast<int>(cell.level));
    const std::uint32_t c[3] = {cell.x + (corner & 1), cell.y + ((corner >> 1) & 1),
                                cell.z + ((corner >> 2) & 1)};
    for (int a = 0; a < 3; ++a) q[a] = double(info.root_min[a]) + e * c[a];
}

}  // namespace prt::iso
