// PointRT preprocess: exact k-NN tile by tile with a halo (tiled_knn.h, issue 17).
#include "tiled_knn.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "kd_tree.h"
#include "morton.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"
#include "radix_sort.h"
#include "spill_file.h"

namespace prt::pre {

namespace {

struct Record {
    float x, y, z;
    std::uint32_t index;
};
static_assert(sizeof(Record) == 16);

constexpr double k_inf = std::numeric_limits<double>::infinity();

/// A run of a tile's records (Morton order within the tile) and their bounding box: halos and
/// scans read only the blocks that meet their box.
struct Block {
    std::uint64_t begin, end;
    float lo[3], hi[3];
};
constexpr std::size_t k_block = 1024;

float coord(const pool::Float3& p, int a) {
    return a == 0 ? p.x : a == 1 ? p.y : p.z;
}

/// The halo that holds every point whose computed squared distance is <= d2: sqrt(d2) with a
/// relative margin for the float rounding of the distance and an absolute one for underflow.
double halo_of(double d2) {
    return std::sqrt(d2) * (1.0 + 1e-5) + 1e-15;
}

/// Tiles: a kd partition of space with 2^depth leaves (heap-ordered internal nodes), split at the
/// medians of a regular sample. A point with coordinate >= split goes to the upper child.
struct Partition {
    unsigned depth = 0;
    std::vector<float> split;
    std::vector<std::uint8_t> axis;
    std::vector<std::array<double, 3>> lo, hi;  ///< per tile: its region (+-inf at the outside)

    std::size_t tiles() const { return std::size_t{1} << depth; }
    std::uint32_t tile_of(const pool::Float3& p) const {
        std::size_t node = 0;
        for (unsigned d = 0; d < depth; ++d)
            node = coord(p, axis[node]) < split[node] ? 2 * node + 1 : 2 * node + 2;
        return static_cast<std::uint32_t>(node - (tiles() - 1));
    }

    void build(std::vector<pool::Float3>& sample, std::size_t node, std::size_t b, std::size_t e, unsigned d,
               std::array<double, 3> rlo, std::array<double, 3> rhi) {
        if (d == depth) {
            const std::size_t t = node - (tiles() - 1);
            lo[t] = rlo;
            hi[t] = rhi;
            return;
        }
        int a = 0;
        float s = std::numeric_limits<float>::infinity();  // an empty sample range: all go low
        if (e > b) {
            float l[3] = {sample[b].x, sample[b].y, sample[b].z}, h[3] = {l[0], l[1], l[2]};
            for (std::size_t i = b; i < e; ++i)
                for (int c = 0; c < 3; ++c) {
                    l[c] = std::min(l[c], coord(sample[i], c));
                    h[c] = std::max(h[c], coord(sample[i], c));
                }
            for (int c = 1; c < 3; ++c)
                if (h[c] - l[c] > h[a] - l[a]) a = c;
            const std::size_t mid = b + (e - b) / 2;
            std::nth_element(
                sample.begin() + std::ptrdiff_t(b), sample.begin() + std::ptrdiff_t(mid),
                sample.begin() + std::ptrdiff_t(e),
                [a](const pool::Float3& p, const pool::Float3& q) { return coord(p, a) < coord(q, a); });
            s = coord(sample[mid], a);
        }
        split[node] = s;
        axis[node] = static_cast<std::uint8_t>(a);
        const std::size_t mid = b + (e - b) / 2;
        std::array<double, 3> lhi = rhi, rlo2 = rlo;
        lhi[a] = s;
        rlo2[a] = s;
        build(sample, 2 * node + 1, b, mid, d + 1, rlo, lhi);
        build(sample, 2 * node + 2, mid, e, d + 1, rlo2, rhi);
    }
};

/// Distance from q to the outside of a region (inf when it has no finite face), and the face it
/// is nearest: 2 * axis for the low face, 2 * axis + 1 for the high one (6: no finite face).
double nearest_face(const float q[3], const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                    int& face) {
    double b = k_inf;
    face = 6;
    for (int a = 0; a < 3; ++a) {
        if (std::isfinite(lo[a]) && double(q[a]) - lo[a] < b) b = double(q[a]) - lo[a], face = 2 * a;
        if (std::isfinite(hi[a]) && hi[a] - double(q[a]) < b) b = hi[a] - double(q[a]), face = 2 * a + 1;
    }
    return b;
}
double border_distance(const float q[3], const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
    int face;
    return nearest_face(q, lo, hi, face);
}

/// The k best candidates by (squared distance, index), exactly as KdTree's search keeps them.
using Best = KdTree<float>::Best;

class Tiler {
public:
    Tiler(std::span<const pool::Float3> positions, const TiledKnnParams& params,
          const std::function<void(const KnnBatch&)>& visit,
          const std::function<void(std::uint64_t)>& progress, TiledKnnStats& stats)
        : m_pos(positions),
          m_params(params),
          m_k(params.k),
          m_visit(visit),
          m_progress(progress),
          m_stats(stats) {
        m_threads = resolve_threads(params.threads);
        m_max_gathered =
            std::max<std::uint64_t>(params.memory / tiled_knn_bytes_per_point(m_k), 4 * (m_k + 1));
        m_tile_points =
            params.tile_points ? params.tile_points : std::max<std::uint64_t>(m_max_gathered / 2, m_k + 1);
        m_stats.tile_points = m_tile_points;
    }

    void run() {
        const double t0 = tool::now_seconds();
        partition();
        bucket();
        const double t1 = tool::now_seconds();
        m_stats.seconds_bucket = t1 - t0;
        for (std::size_t t = 0; t < m_part.tiles(); ++t) {
            tile(t);
            m_records.drop();
            if (m_params.positions_mapped) drop_pages(m_pos.data(), m_pos.size_bytes());
        }
        m_stats.seconds_search = tool::now_seconds() - t1;
    }

private:
    void partition() {
        const std::size_t n = m_pos.size();
        const std::uint64_t want = (n + m_tile_points - 1) / m_tile_points;
        while ((std::uint64_t{1} << m_part.depth) < want && m_part.depth < 20) ++m_part.depth;
        // A regular sample of at least 64 points per tile (all points when the set is small).
        const std::size_t sample_size =
            std::min<std::size_t>(n, std::max<std::size_t>(64 * m_part.tiles(), 1 << 20));
        std::vector<pool::Float3> sample(sample_size);
        for (std::size_t i = 0; i < sample_size; ++i) sample[i] = m_pos[i * n / sample_size];
        const std::size_t internal = m_part.tiles() - 1;
        m_part.split.assign(internal, 0.0f);
        m_part.axis.assign(internal, 0);
        m_part.lo.resize(m_part.tiles());
        m_part.hi.resize(m_part.tiles());
        m_part.build(sample, 0, 0, sample.size(), 0, {-k_inf, -k_inf, -k_inf}, {k_inf, k_inf, k_inf});
        m_stats.tiles = m_part.tiles();
    }

    /// Counting pass and scatter pass: records sorted by tile, in index order within a tile.
    void bucket() {
        const std::size_t n = m_pos.size(), tiles = m_part.tiles();
        const std::size_t chunks = std::min<std::size_t>(std::max<std::size_t>(1, n / 65536), 8 * m_threads);
        std::vector<std::uint64_t> counts(chunks * tiles, 0);
        // Both passes: chunk c's points in index order, each step's position pages dropped after it
        // (`visit(c, i)` per point, `after_step()` after each step).
        const auto over_chunks = [&](auto&& visit, auto&& after_step) {
            parallel_chunks(chunks, 1, m_threads, [&](std::size_t cb, std::size_t ce, unsigned) {
                for (std::size_t c = cb; c < ce; ++c) {
                    const std::size_t b = c * n / chunks, e = (c + 1) * n / chunks;
                    for (std::size_t s = b; s < e; s += k_step) {
                        const std::size_t se = std::min(e, s + k_step);
                        for (std::size_t i = s; i < se; ++i) visit(c, i);
                        drop_positions(s, se);
                        after_step();
                    }
                }
            });
        };
        over_chunks([&](std::size_t c, std::size_t i) { ++counts[c * tiles + m_part.tile_of(m_pos[i])]; },
                    [] {});
        m_begin.assign(tiles + 1, 0);
        for (std::size_t t = 0; t < tiles; ++t) {
            std::uint64_t at = m_begin[t];
            for (std::size_t c = 0; c < chunks; ++c) {
                const std::uint64_t v = counts[c * tiles + t];
                counts[c * tiles + t] = at;  // becomes the chunk's cursor in tile t
                at += v;
            }
            m_begin[t + 1] = at;
        }
        m_records =
            SpillFile(m_params.spill_folder, std::uint64_t(n) * sizeof(Record), "the points sorted by tile");
        Record* out = reinterpret_cast<Record*>(m_records.data());
        over_chunks(
            [&](std::size_t c, std::size_t i) {
                const pool::Float3& p = m_pos[i];
                out[counts[c * tiles + m_part.tile_of(p)]++] = {p.x, p.y, p.z, static_cast<std::uint32_t>(i)};
            },
            [&] { m_records.drop(); });  // written records stay in the file (a shared mapping)
        m_records.drop();
        if (m_params.positions_mapped) drop_pages(m_pos.data(), m_pos.size_bytes());
        // Within each tile: Morton order, then blocks of records with their boxes (order_tile).
        m_block_begin.assign(tiles + 1, 0);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> keys;
        std::vector<Record> sorted;
        for (std::size_t t = 0; t < tiles; ++t) order_tile(t, out, keys, sorted);
    }

    /// Tile t's records in Morton order (10 bits per axis over the tile's bounding box; equal codes
    /// in index order, the order the scatter wrote them in: the radix sort is stable), then cut into
    /// blocks of k_block records with their boxes. Each step runs over the tile's records in
    /// parallel; the order and the blocks are those of a serial sort by (code, index).
    void order_tile(std::size_t t, Record* out, std::vector<std::pair<std::uint32_t, std::uint32_t>>& keys,
                    std::vector<Record>& sorted) {
        constexpr std::size_t k_chunk = std::size_t{1} << 16;
        Record* r = out + m_begin[t];
        const std::size_t m = m_begin[t + 1] - m_begin[t];
        const std::size_t chunks = (m + k_chunk - 1) / k_chunk;
        constexpr float k_max = std::numeric_limits<float>::max();
        std::vector<std::array<float, 6>> boxes(chunks, {k_max, k_max, k_max, -k_max, -k_max, -k_max});
        parallel_chunks(m, k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
            std::array<float, 6>& box = boxes[b / k_chunk];
            for (std::size_t i = b; i < e; ++i)
                for (int a = 0; a < 3; ++a) {
                    box[a] = std::min(box[a], (&r[i].x)[a]);
                    box[3 + a] = std::max(box[3 + a], (&r[i].x)[a]);
                }
        });
        float lo[3] = {k_max, k_max, k_max}, hi[3] = {-k_max, -k_max, -k_max};
        for (const std::array<float, 6>& box : boxes)
            for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], box[a]), hi[a] = std::max(hi[a], box[3 + a]);
        keys.resize(m);
        parallel_chunks(m, k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t i = b; i < e; ++i) {
                std::uint32_t c[3];
                for (int a = 0; a < 3; ++a) {
                    const double ext = double(hi[a]) - double(lo[a]);
                    const double f = ext > 0 ? (double((&r[i].x)[a]) - lo[a]) / ext : 0.0;
                    c[a] = static_cast<std::uint32_t>(std::clamp(f * 1024.0, 0.0, 1023.0));
                }
                keys[i] = {static_cast<std::uint32_t>(spread_bits21(c[0]) | spread_bits21(c[1]) << 1 |
                                                      spread_bits21(c[2]) << 2),
                           static_cast<std::uint32_t>(i)};
            }
        });
        radix_sort_by(keys, 30, m_threads,
                      [](const std::pair<std::uint32_t, std::uint32_t>& k) { return k.first; });
        sorted.resize(m);
        parallel_chunks(m, k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t i = b; i < e; ++i) sorted[i] = r[keys[i].second];
        });
        parallel_chunks(m, k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
            std::copy(sorted.begin() + std::ptrdiff_t(b), sorted.begin() + std::ptrdiff_t(e), r + b);
        });
        const std::size_t first = m_blocks.size(), blocks = (m + k_block - 1) / k_block;
        m_blocks.resize(first + blocks);
        parallel_chunks(blocks, 64, m_threads, [&](std::size_t jb, std::size_t je, unsigned) {
            for (std::size_t j = jb; j < je; ++j) {
                const std::size_t b = j * k_block, e = std::min(m, b + k_block);
                Block& block = m_blocks[first + j];
                block = Block{m_begin[t] + b, m_begin[t] + e, {}, {}};
                for (int a = 0; a < 3; ++a) block.lo[a] = block.hi[a] = (&r[b].x)[a];
                for (std::size_t i = b; i < e; ++i)
                    for (int a = 0; a < 3; ++a) {
                        block.lo[a] = std::min(block.lo[a], (&r[i].x)[a]);
                        block.hi[a] = std::max(block.hi[a], (&r[i].x)[a]);
                    }
            }
        });
        m_block_begin[t + 1] = m_blocks.size();
        drop_pages(r, m * sizeof(Record));
    }

    /// Calls f(record) for every record of the blocks meeting [lo, hi] (tiles whose region meets it).
    template <class F>
    bool for_records_in(const double lo[3], const double hi[3], F&& f) const {
        const Record* all = reinterpret_cast<const Record*>(m_records.data());
        for (std::size_t j = 0; j < m_part.tiles(); ++j) {
            bool meets = true;
            for (int a = 0; a < 3; ++a)
                if (m_part.lo[j][a] > hi[a] || m_part.hi[j][a] < lo[a]) meets = false;
            if (!meets) continue;
            for (std::size_t bi = m_block_begin[j]; bi < m_block_begin[j + 1]; ++bi) {
                const Block& b = m_blocks[bi];
                if (b.lo[0] > hi[0] || b.hi[0] < lo[0] || b.lo[1] > hi[1] || b.hi[1] < lo[1] ||
                    b.lo[2] > hi[2] || b.hi[2] < lo[2])
                    continue;
                for (std::uint64_t i = b.begin; i < b.end; ++i)
                    if (!f(all[i])) return false;
            }
        }
        return true;
    }

    static constexpr std::size_t k_step = std::size_t{1} << 20;  ///< points between page drops

    void drop_positions(std::size_t b, std::size_t e) const {
        if (m_params.positions_mapped) drop_pages(m_pos.data() + b, (e - b) * sizeof(pool::Float3));
    }

    std::span<const Record> tile_records(std::size_t t) const {
        const Record* r = reinterpret_cast<const Record*>(m_records.data());
        return {r + m_begin[t], static_cast<std::size_t>(m_begin[t + 1] - m_begin[t])};
    }

    void sample_memory() {
        m_stats.peak_anon_rss = std::max(m_stats.peak_anon_rss, current_anon_rss_bytes());
    }

    void report(std::uint64_t done) {
        m_done += done;
        if (m_progress) m_progress(m_done);
    }

    /// Records by increasing index (indices are unique, so any sort gives this order): a parallel
    /// radix sort for large sets, std::sort for small ones (halo groups of a few points).
    void sort_by_index(std::vector<Record>& recs) const {
        if (recs.size() < (std::size_t{1} << 16)) {
            std::sort(recs.begin(), recs.end(),
                      [](const Record& p, const Record& q) { return p.index < q.index; });
            return;
        }
        const auto bits = static_cast<std::uint32_t>(std::bit_width(std::uint64_t(m_pos.size())));
        radix_sort_by(recs, bits, m_threads, [](const Record& r) { return r.index; });
    }

    /// One tile: round 1 over its own points, then the halo groups.
    void tile(std::size_t t) {
        std::vector<Record> recs(tile_records(t).begin(), tile_records(t).end());
        const std::size_t m = recs.size();
        if (m == 0) return;
        sort_by_index(recs);
        const std::uint32_t k = m_k;
        std::vector<pool::Float3> pts(m);
        std::vector<std::uint32_t> global(m);
        parallel_chunks(m, std::size_t{1} << 16, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t i = b; i < e; ++i) {
                pts[i] = {recs[i].x, recs[i].y, recs[i].z};
                global[i] = recs[i].index;
            }
        });
        m_stats.max_gathered = std::max<std::uint64_t>(m_stats.max_gathered, m);
        std::vector<Failing> failing;
        if (m > k) {
            const KdTree<float> tree(
                m, [&](std::size_t i, float c[3]) { c[0] = pts[i].x, c[1] = pts[i].y, c[2] = pts[i].z; },
                m_threads);
            std::vector<std::uint32_t> nb(m * std::size_t(k));
            std::vector<float> dd(m * std::size_t(k));
            std::vector<std::uint8_t> ok(m, 0);
            parallel_chunks(m, 1024, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
                for (std::size_t i = b; i < e; ++i) {
                    const std::uint32_t found = tree.nearest(static_cast<std::uint32_t>(i), k, nullptr,
                                                             nb.data() + i * k, dd.data() + i * k);
                    const float q[3] = {pts[i].x, pts[i].y, pts[i].z};
                    ok[i] = found == k &&
                            halo_of(dd[i * k + k - 1]) < border_distance(q, m_part.lo[t], m_part.hi[t]);
                }
            });
            std::vector<std::uint32_t> queries;
            std::size_t w = 0;
            for (std::size_t i = 0; i < m; ++i) {
                if (!ok[i]) {
                    failing.push_back({double(dd[i * k + k - 1]), static_cast<std::uint32_t>(i)});
                    continue;
                }
                queries.push_back(static_cast<std::uint32_t>(i));
                if (w != i) {
                    std::copy_n(nb.data() + i * k, k, nb.data() + w * k);
                    std::copy_n(dd.data() + i * k, k, dd.data() + w * k);
                }
                ++w;
            }
            nb.resize(w * k);
            dd.resize(w * k);
            sample_memory();
            m_visit(KnnBatch{pts, global, queries, nb, dd});
            report(queries.size());
        } else {
            for (std::size_t i = 0; i < m; ++i) failing.push_back({k_inf, static_cast<std::uint32_t>(i)});
        }
        if (failing.empty()) return;
        m_stats.halo_queries += failing.size();

        // Round 2, by the tile face each failing point is nearest (its halo reaches out through
        // that face): six thin slabs, each gathered with its halo, instead of one set spanning the
        // whole tile (the boxes of points from every face). Points with no finite face (a lone
        // tile) or no bound (fewer than k + 1 points in the tile) form their own group.
        std::array<std::vector<Failing>, 7> by_face;
        for (const Failing& f : failing) {
            const float q[3] = {pts[f.second].x, pts[f.second].y, pts[f.second].z};
            int face;
            nearest_face(q, m_part.lo[t], m_part.hi[t], face);
            by_face[std::isfinite(f.first) ? face : 6].push_back(f);
        }
        failing = {};
        const std::uint64_t cap = std::min<std::uint64_t>(m_max_gathered, m + m / 2 + 4096);
        for (std::vector<Failing>& group_points : by_face) {
            std::sort(group_points.begin(), group_points.end());
            round2(pts, global, group_points, 0, group_points.size(), cap);
            group_points = {};
        }
    }

    using Failing = std::pair<double, std::uint32_t>;  ///< (tile-only k-th distance^2, local index)
    /// Runs of at most this many points are scanned, not gathered: a run of a few points of large
    /// bound (outliers) gathered a wide region and built a kd-tree for a handful of queries (on an
    /// 11M-point scan-like room at --memory 128M, groups of 64 points or fewer held 70 % of all the
    /// points gathered, for 0.1 % of the queries).
    static constexpr std::size_t k_scan_run = 32;

    /// Round 2 over failing points sorted by increasing bound u. Each step takes the longest run
    /// [start, c) whose box (the run's bounding box grown by the halo of u[c - 1]) holds at most
    /// `cap` points by the block count (an upper bound, no record read), searches it as one group,
    /// and goes on with the rest. When not even one more point fits, the rest is split in two at
    /// the middle of its box's widest axis and each half goes the same way (the few points of
    /// large bound, outliers, end in small groups of their own). Runs of at most k_scan_run
    /// points, and a point that does not fit alone (or below 64 splits), are searched by streaming
    /// scans (in parallel).
    void round2(const std::vector<pool::Float3>& pts, const std::vector<std::uint32_t>& global,
                std::vector<Failing>& failing, std::size_t begin, std::size_t end, std::uint64_t cap,
                int depth = 0) {
        std::size_t start = begin;
        // box[i]: the bounding box of [start, start + i] (floats, as the coordinates: 24 bytes a
        // point, the one working array round 2 adds to the tile's)
        std::vector<std::array<float, 6>> box;
        while (start < end) {
            const std::size_t n = end - start;
            box.resize(n);
            for (std::size_t i = 0; i < n; ++i) {
                const pool::Float3& q = pts[failing[start + i].second];
                for (int c = 0; c < 3; ++c) {
                    const float v = coord(q, c);
                    box[i][c] = i == 0 ? v : std::min(box[i - 1][c], v);
                    box[i][3 + c] = i == 0 ? v : std::max(box[i - 1][3 + c], v);
                }
            }
            auto bounds = [&](std::size_t e, double lo[3], double hi[3]) {  // the box of [start, e)
                const std::array<float, 6>& f = box[e - 1 - start];
                for (int c = 0; c < 3; ++c) lo[c] = f[c], hi[c] = f[3 + c];
            };
            auto fits = [&](std::size_t e) {
                const double u = failing[e - 1].first;
                double lo[3], hi[3];
                bounds(e, lo, hi);
                return std::isfinite(u) && count_upper(lo, hi, halo_of(u), cap) <= cap;
            };
            std::size_t good = start, bad = end + 1;  // fits(good) (or good == start)
            if (fits(end)) {
                good = end;
            } else {
                bad = end;
                while (bad - good > 1) {
                    const std::size_t mid = good + (bad - good) / 2;
                    if (fits(mid))
                        good = mid;
                    else
                        bad = mid;
                }
            }
            if (good > start && good - start <= k_scan_run) {  // a few points: scans, no kd-tree
                scan_all(pts, global, failing, start, good);
                start = good;
                continue;
            }
            if (good > start) {
                double lo[3], hi[3];
                bounds(good, lo, hi);
                if (group(pts, global, failing, start, good, lo, hi, halo_of(failing[good - 1].first))) {
                    start = good;
                    continue;
                }
            }
            if (n == 1 || !std::isfinite(failing[start].first) || depth >= 64) break;
            // Not even the next point fits with the others' box: split the rest in two at the
            // middle of its box's widest axis, in place (a stable partition keeps each half in
            // increasing bound order).
            const std::array<float, 6> b = box[n - 1];
            box = {};
            int axis = 0;
            for (int c = 1; c < 3; ++c)
                if (b[3 + c] - b[c] > b[3 + axis] - b[axis]) axis = c;
            if (!(b[3 + axis] > b[axis])) break;  // coincident points: no smaller box
            float split = b[axis] + 0.5f * (b[3 + axis] - b[axis]);
            if (!(split > b[axis])) split = b[3 + axis];  // adjacent floats: the lowest alone
            const auto first = failing.begin() + std::ptrdiff_t(start);
            const auto mid =
                std::stable_partition(first, failing.begin() + std::ptrdiff_t(end),
                                      [&](const Failing& f) { return coord(pts[f.second], axis) < split; });
            const std::size_t cut = start + static_cast<std::size_t>(mid - first);
            round2(pts, global, failing, start, cut, cap, depth + 1);
            round2(pts, global, failing, cut, end, cap, depth + 1);
            return;
        }
        // What is left does not fit even split (or is one point, or unbounded): scanned, each
        // within its own halo.
        scan_all(pts, global, failing, start, end);
    }

    /// The points in the blocks meeting [lo - h, hi + h], counted up to just above `cap`.
    std::uint64_t count_upper(const double lo[3], const double hi[3], double h, std::uint64_t cap) const {
        double glo[3], ghi[3];
        for (int a = 0; a < 3; ++a) glo[a] = lo[a] - h, ghi[a] = hi[a] + h;
        std::uint64_t count = 0;
        for (std::size_t j = 0; j < m_part.tiles() && count <= cap; ++j) {
            bool meets = true;
            for (int a = 0; a < 3; ++a)
                if (m_part.lo[j][a] > ghi[a] || m_part.hi[j][a] < glo[a]) meets = false;
            if (!meets) continue;
            for (std::size_t bi = m_block_begin[j]; bi < m_block_begin[j + 1] && count <= cap; ++bi) {
                const Block& b = m_blocks[bi];
                if (b.lo[0] > ghi[0] || b.hi[0] < glo[0] || b.lo[1] > ghi[1] || b.hi[1] < glo[1] ||
                    b.lo[2] > ghi[2] || b.hi[2] < glo[2])
                    continue;
                count += b.end - b.begin;
            }
        }
        return count;
    }

    /// Gathers the points inside [lo - h, hi + h] (by increasing index) unless more than `cap`.
    bool gather(const double lo[3], const double hi[3], double h, std::uint64_t cap,
                std::vector<Record>& out) const {
        out.clear();
        double glo[3], ghi[3];
        for (int a = 0; a < 3; ++a) glo[a] = lo[a] - h, ghi[a] = hi[a] + h;
        const bool fits = for_records_in(glo, ghi, [&](const Record& r) {
            const double v[3] = {r.x, r.y, r.z};
            if (v[0] < glo[0] || v[0] > ghi[0] || v[1] < glo[1] || v[1] > ghi[1] || v[2] < glo[2] ||
                v[2] > ghi[2])
                return true;
            if (out.size() >= cap) return false;
            out.push_back(r);
            return true;
        });
        if (!fits) return false;
        sort_by_index(out);
        return true;
    }

    /// The failing points [a, b), whose bounding box is [lo, hi], with halo h: one kd-tree over that
    /// box grown by h. False when that set is over the memory.
    bool group(const std::vector<pool::Float3>& pts, const std::vector<std::uint32_t>& global,
               const std::vector<Failing>& failing, std::size_t a, std::size_t b, const double lo[3],
               const double hi[3], double h) {
        const std::uint64_t cap =
            b - a <= 64 ? m_max_gathered
                        : std::min<std::uint64_t>(m_max_gathered, pts.size() + pts.size() / 2 + 4096);
        std::vector<Record> set;
        if (!gather(lo, hi, h, cap, set)) return false;
        const std::uint32_t k = m_k;
        const std::size_t g = set.size();
        m_stats.max_gathered = std::max<std::uint64_t>(m_stats.max_gathered, g);
        ++m_stats.halo_groups;
        m_stats.gathered += g;
        std::vector<pool::Float3> gp(g);
        std::vector<std::uint32_t> gi(g);
        parallel_chunks(g, std::size_t{1} << 16, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t i = b; i < e; ++i) gp[i] = {set[i].x, set[i].y, set[i].z}, gi[i] = set[i].index;
        });
        set = {};
        std::vector<std::uint32_t> queries(b - a);
        for (std::size_t i = a; i < b; ++i) {
            const auto it = std::lower_bound(gi.begin(), gi.end(), global[failing[i].second]);
            if (it == gi.end() || *it != global[failing[i].second])
                throw Error("internal: tiled k-NN lost a query point");
            queries[i - a] = static_cast<std::uint32_t>(it - gi.begin());
        }
        const KdTree<float> tree(
            g, [&](std::size_t i, float c[3]) { c[0] = gp[i].x, c[1] = gp[i].y, c[2] = gp[i].z; }, m_threads);
        std::vector<std::uint32_t> nb(queries.size() * std::size_t(k));
        std::vector<float> dd(queries.size() * std::size_t(k));
        std::atomic<bool> short_found{false};
        parallel_chunks(queries.size(), 256, m_threads, [&](std::size_t qb, std::size_t qe, unsigned) {
            for (std::size_t q = qb; q < qe; ++q)
                if (tree.nearest(queries[q], k, nullptr, nb.data() + q * k, dd.data() + q * k) != k)
                    short_found = true;
        });
        if (short_found) throw Error("internal: tiled k-NN found fewer than k neighbours in a halo");
        sample_memory();
        m_visit(KnnBatch{gp, gi, queries, nb, dd});
        report(queries.size());
        return true;
    }

    /// The k nearest other points of p by a streaming scan of the records within its bound (all of
    /// them when unbounded), into index/distance2; returns how many were found. Reads only.
    std::uint32_t scan_best(const pool::Float3& p, std::uint32_t self, double u, std::uint32_t* index,
                            float* distance2) const {
        Best best{m_k, 0, index, distance2};
        const double h = std::isfinite(u) ? halo_of(u) : k_inf;
        const float q[3] = {p.x, p.y, p.z};
        const double slo[3] = {q[0] - h, q[1] - h, q[2] - h}, shi[3] = {q[0] + h, q[1] + h, q[2] + h};
        for_records_in(slo, shi, [&](const Record& r) {
            const float dx = r.x - q[0], dy = r.y - q[1], dz = r.z - q[2];
            const float d2 = dx * dx + dy * dy + dz * dz;
            if (r.index != self) best.offer(d2, r.index);
            return true;
        });
        return best.count;
    }

    /// The failing points [a, b) by streaming scans, each within its own bound: the scans in
    /// parallel (a few thousand points at a time), the batches visited in order from this thread.
    void scan_all(const std::vector<pool::Float3>& pts, const std::vector<std::uint32_t>& global,
                  const std::vector<Failing>& failing, std::size_t a, std::size_t b) {
        const std::uint32_t k = m_k;
        constexpr std::size_t k_batch = 4096;
        std::vector<std::uint32_t> index;
        std::vector<float> distance2;
        for (std::size_t first = a; first < b; first += k_batch) {
            const std::size_t n = std::min(k_batch, b - first);
            index.assign(n * k, 0);
            distance2.assign(n * k, 0.0f);
            std::atomic<bool> short_found{false};
            parallel_chunks(n, 1, m_threads, [&](std::size_t s, std::size_t e, unsigned) {
                for (std::size_t i = s; i < e; ++i) {
                    const Failing& f = failing[first + i];
                    if (scan_best(pts[f.second], global[f.second], f.first, index.data() + i * k,
                                  distance2.data() + i * k) != k)
                        short_found = true;
                }
            });
            if (short_found) throw Error("internal: tiled k-NN scan found fewer than k neighbours");
            for (std::size_t i = 0; i < n; ++i)
                visit_scanned(global[failing[first + i].second], index.data() + i * k,
                              distance2.data() + i * k);
        }
    }

    /// One scanned point's batch: the point and its neighbours, in index order.
    void visit_scanned(std::uint32_t self, const std::uint32_t* index, const float* distance2) {
        ++m_stats.scanned;
        const std::uint32_t k = m_k;
        std::vector<std::uint32_t> gi(index, index + k);
        gi.push_back(self);
        std::sort(gi.begin(), gi.end());
        std::vector<pool::Float3> gp(gi.size());
        for (std::size_t i = 0; i < gi.size(); ++i) gp[i] = m_pos[gi[i]];
        auto local = [&](std::uint32_t g) {
            return static_cast<std::uint32_t>(std::lower_bound(gi.begin(), gi.end(), g) - gi.begin());
        };
        const std::uint32_t query = local(self);
        std::vector<std::uint32_t> nb(k);
        for (std::uint32_t j = 0; j < k; ++j) nb[j] = local(index[j]);
        sample_memory();
        m_visit(KnnBatch{gp, gi, std::span<const std::uint32_t>(&query, 1), nb,
                         std::span<const float>(distance2, k)});
        report(1);
    }

    std::span<const pool::Float3> m_pos;
    const TiledKnnParams& m_params;
    std::uint32_t m_k;
    const std::function<void(const KnnBatch&)>& m_visit;
    const std::function<void(std::uint64_t)>& m_progress;
    TiledKnnStats& m_stats;
    unsigned m_threads = 1;
    std::uint64_t m_max_gathered = 0, m_tile_points = 0, m_done = 0;
    Partition m_part;
    SpillFile m_records;
    std::vector<std::uint64_t> m_begin;
    std::vector<Block> m_blocks;
    std::vector<std::uint64_t> m_block_begin;  ///< per tile: its first block
};

}  // namespace

std::uint64_t tiled_knn_bytes_per_point(std::uint32_t k) {
    return 64 + 16 * std::uint64_t(k);
}

void tiled_knn(std::span<const pool::Float3> positions, const TiledKnnParams& params,
               const std::function<void(const KnnBatch&)>& visit,
               const std::function<void(std::uint64_t)>& progress, TiledKnnStats* stats) {
    const std::size_t n = positions.size();
    if (params.k == 0) throw Error("k-NN: k must be at least 1");
    if (n <= params.k)
        throw Error("k-NN: " + std::to_string(n) + " points, need more than k = " + std::to_string(params.k));
    if (n >= std::numeric_limits<std::uint32_t>::max())
        throw Error("k-NN: " + std::to_string(n) + " points, at most 4294967294 are supported");
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(positions[i].x) || !std::isfinite(positions[i].y) ||
            !std::isfinite(positions[i].z))
            throw Error("k-NN: point " + std::to_string(i) + " has a non-finite position");
        if (params.positions_mapped && (i + 1) % (std::size_t{1} << 20) == 0)
            drop_pages(positions.data() + i + 1 - (std::size_t{1} << 20),
                       (std::size_t{1} << 20) * sizeof(pool::Float3));
    }
    TiledKnnStats local;
    local.points = n;
    Tiler(positions, params, visit, progress, local).run();
    if (stats) *stats = local;
}

}  // namespace prt::pre
