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
//                (child_overlap_mask; most points from their centre alone, place()), counting
//                points per cell and chunk; each inner cell's exact count and radius sum checks
//                that build_octree splits it (octree_splits_node)
//   5. scatter   one pass: each point's record into its cells' ranges of the spill files (a file
//                per run of whole cells), in input order within each cell (chunks write disjoint
//                ranges, so in parallel); a point the count pass found in one cell only is not
//                classified again
//   6. cells     in depth-first (Morton) order: build_octree_cell, cull_octree over the part (a
//                leaf's probes depend on its cell only), build_brick_part; the payloads appended to
//                a spill file; each part of the records closed (SpillReleaser) once its cells are built
//   7. assemble  the top tree breadth first over the partition and the cells' top trees (the
//                numbering cut_top_tree gives), the table in that brick order, the LOD discs above the
//                bricks (finish_bricks); the payloads are copied into the pool as it is written
//                (PayloadSource)
#include "bricks_from_points.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "buffer.h"
#include "morton.h"
#include "prt/atomic_file.h"
#include "prt/error.h"
#include "prt/formats/pool.h"
#include "prt/mapped_file.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"

namespace prt::pre {

namespace {

constexpr std::uint32_t k_histogram_level = 6;  // 262144 cells
constexpr std::size_t k_chunk = std::size_t(1) << 20;
constexpr std::uint32_t k_no_cell = 0xFFFFFFFFu;
/// m_point_cell: a point in more than one cell (classified again by the scatter).
constexpr std::uint32_t k_several_cells = 0xFFFFFFFEu;

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

// -- the staged build's files (issue 21) ------------------------------------------------------------
// plan.bin: "PRTPLAN1", then one blob (below) and its checksum (pool::checksum, XXH3).
// records.bin: the Record array of step 5, cell after cell (plan.bin gives each cell's range), then
//   the plan id (8 bytes).
// cells-FIRST-LAST.bin: the payloads of cells [FIRST, LAST) one after the other, then the blob of
//   their plan id, CellBricks and statistics, then a footer: the blob's offset, size and checksum,
//   "PRTCELL1".
// The plan id (random, in plan.bin's blob too) ties the three together: a stage that finds files of
// two plans (a plan stage ran while cells were being built) refuses them, naming the file.
// A blob is a sequence of trivially copyable values and vectors of them (a vector: its length, then
// its elements), in host byte order: the folder is read by the same build of prt-bricks on the same
// kind of machine (a cluster's workers).
constexpr std::uint64_t k_plan_magic = 0x314e414c50545250ull;   // "PRTPLAN1"
constexpr std::uint64_t k_cells_magic = 0x314c4c4543545250ull;  // "PRTCELL1"
constexpr std::uint32_t k_staged_version = 3;  // 3: the plan id in plan.bin, records.bin and parts

class BlobWriter {
public:
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto* p = reinterpret_cast<const std::byte*>(&v);
        m_bytes.insert(m_bytes.end(), p, p + sizeof(T));
    }
    template <class T>
    void put_vector(const std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        put(std::uint64_t(v.size()));
        const auto* p = reinterpret_cast<const std::byte*>(v.data());
        m_bytes.insert(m_bytes.end(), p, p + v.size() * sizeof(T));
    }
    void put_string(const std::string& t) { put_vector(std::vector<char>(t.begin(), t.end())); }
    const std::vector<std::byte>& bytes() const { return m_bytes; }

private:
    std::vector<std::byte> m_bytes;
};

class BlobReader {
public:
    BlobReader(std::span<const std::byte> bytes, std::string label)
        : m_bytes(bytes), m_label(std::move(label)) {}
    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        T v;
        std::memcpy(&v, take(sizeof(T)), sizeof(T));
        return v;
    }
    template <class T>
    std::vector<T> get_vector() {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto n = get<std::uint64_t>();
        if (n > (m_bytes.size() - m_at) / sizeof(T)) fail();
        std::vector<T> v(n);
        if (n > 0) std::memcpy(v.data(), take(n * sizeof(T)), n * sizeof(T));
        return v;
    }
    std::string get_string() {
        const std::vector<char> c = get_vector<char>();
        return {c.begin(), c.end()};
    }
    bool done() const { return m_at == m_bytes.size(); }
    [[noreturn]] void fail() const { throw Error(m_label + ": truncated or not written by this prt-bricks"); }

private:
    const std::byte* take(std::size_t n) {
        if (n > m_bytes.size() - m_at) fail();
        const std::byte* p = m_bytes.data() + m_at;
        m_at += n;
        return p;
    }
    std::span<const std::byte> m_bytes;
    std::string m_label;
    std::size_t m_at = 0;
};

/// Adds the cell counts and times of `from` (one cell's, or a part's) to `to`.
void add_cells(PointBrickStats& to, const PointBrickStats& from) {
    to.cells += from.cells;
    to.cells_culled_on_device += from.cells_culled_on_device;
    to.partition_depth = std::max(to.partition_depth, from.partition_depth);
    to.max_cell_points = std::max(to.max_cell_points, from.max_cell_points);
    to.cell_records += from.cell_records;
    to.stored_splats += from.stored_splats;
    to.culled_splats += from.culled_splats;
    to.octree_seconds += from.octree_seconds;
    to.cull_seconds += from.cull_seconds;
    to.brick_seconds += from.brick_seconds;
    to.payload_write_seconds += from.payload_write_seconds;
}

std::span<const std::byte> bytes_of(const MappedFile& f) {
    return {reinterpret_cast<const std::byte*>(f.data()), f.size()};
}

/// The options a staged build's stages must share (everything that changes the bricks).
std::string staged_fingerprint(const PointBrickParams& p) {
    const CullParams& c = p.culling;
    return "leaf_size=" + std::to_string(p.octree.max_leaf_splats) +
           " max_depth=" + std::to_string(p.octree.max_depth) +
           " replicate=" + std::to_string(p.octree.replicate) +
           " min_cell=" + std::to_string(p.octree.min_cell_ratio) +
           " split_by_centres=" + std::to_string(p.octree.split_by_centres) +
           " cull=" + std::to_string(p.cull) + " directions=" + std::to_string(c.directions) +
           " grid=" + std::to_string(c.grid) + " policy=" + std::to_string(int(c.policy)) +
           " window=" + std::to_string(c.window) + " seed=" + std::to_string(c.seed) +
           " brick_splats=" + std::to_string(p.bricks.brick_splats) +
           " lod_splats=" + std::to_string(p.bricks.lod_splats) +
           " direct=" + std::to_string(int(p.bricks.direct));
}

/// Step 7's payload copy, made while the pool is written (PointBricks::data): the bricks in table
/// order, each padded to k_brick_alignment, from the whole build's payload spill file or the staged
/// build's part files (each brick's own checksum checked as it is read). Gathering them into a spill
/// file first, then hashing it and then writing it, read and wrote the payloads three times (the
/// 500M room: 7.7 GB, 8 s of assembly before the pool's write).
struct PayloadSource {
    struct Brick {
        std::uint32_t part;
        std::uint64_t offset, size, checksum;
    };
    AppendFile payloads;            // the whole build in one process
    std::shared_ptr<SpillReleaser> releaser;  // closing the point records' files, while the pool is written
    std::vector<MappedFile> parts;  // the staged build's parts (then `payloads` is empty)
    std::vector<Brick> bricks;      // in table order
    std::function<void(const char*, std::uint64_t, std::uint64_t)> progress;

    /// Bricks [b, e) one after the other into `to` (padded, zeros between them).
    void read(std::size_t b, std::size_t e, std::byte* to) const {
        for (std::size_t k = b; k < e; ++k) {
            const Brick& br = bricks[k];
            if (parts.empty()) {
                payloads.read(br.offset, to, br.size);
            } else {
                const MappedFile& file = parts[br.part];
                std::memcpy(to, file.data() + br.offset, br.size);
                drop_mapped_pages(file.data() + br.offset, br.size);
                if (pool::checksum({to, static_cast<std::size_t>(br.size)}) != br.checksum)
                    throw Error(file.label() +
                                ": checksum mismatch: corrupt, truncated or not written by this prt-bricks");
            }
            std::memset(to + br.size, 0, pool::brick_padded_size(br.size) - br.size);
            to += pool::brick_padded_size(br.size);
        }
    }

    /// The section to `sink` in batches of about 16 MiB: the next batch is read on another thread
    /// while the writer hashes and writes this one.
    void generate(const pool::PoolWriter::ByteSink& sink) const {
        constexpr std::uint64_t k_batch = std::uint64_t(16) << 20;
        std::vector<std::pair<std::size_t, std::uint64_t>> batches;  // (first brick, bytes)
        for (std::size_t k = 0; k < bricks.size(); ++k) {
            const std::uint64_t n = pool::brick_padded_size(bricks[k].size);
            if (batches.empty() || batches.back().second + n > k_batch) batches.emplace_back(k, 0);
            batches.back().second += n;
        }
        auto end_of = [&](std::size_t g) {
            return g + 1 < batches.size() ? batches[g + 1].first : bricks.size();
        };
        std::vector<std::byte> buffer[2];
        std::exception_ptr failed;
        std::thread reader;
        auto start = [&](std::size_t g) {
            std::vector<std::byte>& to = buffer[g % 2];
            if (to.size() < batches[g].second) to.resize(batches[g].second);
            reader = std::thread([&, g] {
                try {
                    read(batches[g].first, end_of(g), buffer[g % 2].data());
                } catch (...) {
                    failed = std::current_exception();
                }
            });
        };
        if (!batches.empty()) start(0);
        for (std::size_t g = 0; g < batches.size(); ++g) {
            reader.join();
            if (failed) std::rethrow_exception(failed);
            if (g + 1 < batches.size()) start(g + 1);
            try {
                sink(buffer[g % 2].data(), batches[g].second);
            } catch (...) {
                if (reader.joinable()) reader.join();
                throw;
            }
            if (progress) progress("writing bricks", end_of(g), bricks.size());
        }
    }
};

}  // namespace

unsigned cell_workers(const PointBrickParams& params) {
    return params.cell_workers > 0 ? params.cell_workers : resolve_threads(params.threads);
}

std::uint64_t cell_capacity(const PointBrickParams& params) {
    if (params.cell_points > 0) return params.cell_points;
    return std::max<std::uint64_t>(params.memory / (k_cell_bytes_per_point * cell_workers(params)), 1u << 16);
}

namespace {

class Partitioner {
public:
    Partitioner(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                std::span<const float> radii, std::span<const pool::Rgba8> colors,
                const PointBrickParams& params)
        : m_positions(positions),
          m_normals(normals),
          m_radii(radii),
          m_colors(colors),
          m_has_colors(!colors.empty()),
          m_params(params),
          m_threads(resolve_threads(params.threads)),
          m_octree_backend(resolve_octree_backend(params.octree.backend)) {}

    /// Steps 1-5: the partition and the records of each cell, in a temporary spill file or, with
    /// `records_file`, in that named file (the staged build).
    void plan(PointBrickStats& stats, const std::filesystem::path& records_file = {}) {
        const double start = tool::now_seconds();
        double t[5] = {start};
        bounds(stats);  // 1
        t[1] = tool::now_seconds();
        partition(histogram());  // 2, 3
        t[2] = tool::now_seconds();
        count();  // 4
        t[3] = tool::now_seconds();
        scatter(records_file);  // 5
        t[4] = tool::now_seconds();
        for (int k = 0; k < 4; ++k) stats.partition_pass_seconds[k] = t[k + 1] - t[k];
        stats.partition_seconds = tool::now_seconds() - start;
    }

    std::uint32_t cell_count() const { return std::uint32_t(m_cell_nodes.size()); }
    /// A fresh id for a staged plan (random, never 0).
    void new_plan_id() {
        std::random_device rd;
        const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
        m_plan_id = ((std::uint64_t{rd()} << 32) ^ rd() ^ static_cast<std::uint64_t>(now)) | 1u;
    }
    /// Point records over all cells (a point in several cells counts in each).
    std::uint64_t record_count() const { return m_cell_begin.empty() ? 0 : m_cell_begin.back(); }

    /// Step 6 for cells [first, last): each cell's payload goes to `append` (returns its offset in
    /// the payload file, which is part `part`; called by several workers at once).
    void build(std::uint32_t first, std::uint32_t last, std::uint32_t part,
               const std::function<std::uint64_t(std::span<const std::byte>)>& append,
               PointBrickStats& stats) {
        m_cells.resize(cell_count());
        const std::uint64_t begin = m_cell_begin[first], end = m_cell_begin[last];
        // Cells by several workers at once, each with its share of the threads: a cell's build has
        // serial stretches (and GPU culling) that one cell's threads cannot fill (on the H100 host with
        // 16 threads: a 50M room with 1, 2, 4, 8 cells at once 33.7, 19.8, 15.7, 10.8 s; a 200M room
        // with 4, 8, 16 at once 54.0, 46.3, 37.5 s).
        const unsigned workers = std::min<unsigned>(cell_workers(), last - first);
        const unsigned threads = std::max(1u, m_threads / std::max(1u, workers));
        std::atomic<std::uint32_t> next{first};
        std::atomic<std::uint64_t> done{0};
        std::exception_ptr failure;
        // With a releaser (the whole build in one process), each part of the records is closed on its
        // thread once its cells are built (cells go in order, parts are runs of them).
        std::vector<std::atomic<std::uint32_t>> cells_left(m_releaser ? m_record_parts.size() : 0);
        for (std::uint32_t c = first; m_releaser && c < last; ++c) ++cells_left[m_cell_part[c]];
        auto work = [&] {
            try {
                for (std::uint32_t c = next++; c < last; c = next++) {
                    build_cell(c, part, append, stats, threads);
                    if (m_releaser && cells_left[m_cell_part[c]].fetch_sub(1) == 1)
                        m_releaser->release(std::move(m_record_parts[m_cell_part[c]]));
                    const std::uint64_t d = done.fetch_add(m_cell_begin[c + 1] - m_cell_begin[c]) +
                                            (m_cell_begin[c + 1] - m_cell_begin[c]);
                    const std::lock_guard<std::mutex> lock(m_mutex);
                    report("building cells", d, end - begin);
                }
            } catch (...) {
                const std::lock_guard<std::mutex> lock(m_mutex);
                if (!failure) failure = std::current_exception();
                next = last;  // the other workers stop after their cell
            }
        };
        report("building cells", 0, end - begin);
        std::vector<std::thread> pool;
        for (unsigned w = 1; w < workers; ++w) pool.emplace_back(work);
        work();
        for (std::thread& t : pool) t.join();
        if (failure) std::rethrow_exception(failure);
    }

    unsigned cell_workers() const { return pre::cell_workers(m_params); }

    /// The whole build in this process (build_bricks_from_points).
    PointBricks run(PointBrickStats& stats) {
        const double start = tool::now_seconds();
        plan(stats);
        m_payloads = AppendFile(m_params.spill_folder, "the brick payloads");
        m_releaser = std::make_shared<SpillReleaser>();
        build(
            0, cell_count(), 0,
            [&](std::span<const std::byte> b) { return m_payloads.append(b.data(), b.size()); }, stats);
        m_record_parts.clear();  // released part by part already
        const double assembly = tool::now_seconds();
        auto source = std::make_shared<PayloadSource>();
        source->payloads = std::move(m_payloads);
        source->releaser = std::move(m_releaser);
        PointBricks out = assemble(stats, std::move(source));
        stats.seconds = tool::now_seconds() - start;
        stats.assemble_seconds = stats.seconds - (assembly - start);
        return out;
    }

    // -- the staged build (issue 21) ---------------------------------------------------------------
    void save_plan(const std::filesystem::path& folder, const PointBrickStats& stats) const {
        BlobWriter w;
        w.put(k_staged_version);
        w.put(m_plan_id);
        w.put_string(staged_fingerprint(m_params));
        w.put(m_has_colors);
        w.put(m_root);
        w.put_vector(m_nodes);
        w.put_vector(m_cell_nodes);
        w.put_vector(m_cell_begin);
        w.put(stats.points);
        w.put(stats.skipped);
        w.put(stats.partition_seconds);
        AtomicFile f(folder / "plan.bin");
        f.write(&k_plan_magic, sizeof k_plan_magic);
        f.write(w.bytes().data(), w.bytes().size());
        const std::uint64_t sum = pool::checksum(w.bytes());
        f.write(&sum, sizeof sum);
        f.commit();
    }

    /// Reads FOLDER/plan.bin and maps FOLDER/records.bin; returns the plan's statistics.
    PointBrickStats load_plan(const std::filesystem::path& folder) {
        const std::filesystem::path path = folder / "plan.bin";
        if (!std::filesystem::exists(path))
            throw Error(folder.string() + ": no plan.bin (run prt-bricks --stage plan first)");
        const MappedFile file = MappedFile::open(path, MappedFile::Access::random);
        const std::span<const std::byte> all = bytes_of(file);
        std::uint64_t magic = 0, sum = 0;
        if (all.size() < 16) throw Error(path.string() + ": truncated or not written by this prt-bricks");
        std::memcpy(&magic, all.data(), 8);
        std::memcpy(&sum, all.data() + all.size() - 8, 8);
        const std::span<const std::byte> blob = all.subspan(8, all.size() - 16);
        if (magic != k_plan_magic || pool::checksum(blob) != sum)
            throw Error(path.string() +
                        ": checksum mismatch: corrupt, truncated or not written by this prt-bricks");
        BlobReader r(blob, path.string());
        if (r.get<std::uint32_t>() != k_staged_version)
            throw Error(path.string() + ": written by another version of prt-bricks");
        m_plan_id = r.get<std::uint64_t>();
        const std::string planned = r.get_string(), now = staged_fingerprint(m_params);
        if (planned != now)
            throw Error(path.string() + ": planned with other options (" + planned + "; now " + now +
                        "): give every stage the same options");
        m_has_colors = r.get<bool>();
        m_root = r.get<pool::OctreeInfo>();
        m_nodes = r.get_vector<PartNode>();
        m_cell_nodes = r.get_vector<std::uint32_t>();
        m_cell_begin = r.get_vector<std::uint64_t>();
        PointBrickStats stats;
        stats.points = r.get<std::uint64_t>();
        stats.skipped = r.get<std::uint64_t>();
        stats.partition_seconds = r.get<double>();
        if (!r.done() || m_cell_begin.size() != m_cell_nodes.size() + 1) r.fail();
        for (const std::uint32_t n : m_cell_nodes)
            if (n >= m_nodes.size()) r.fail();
        for (std::size_t c = 0; c + 1 < m_cell_begin.size(); ++c)
            if (m_cell_begin[c] > m_cell_begin[c + 1]) r.fail();
        const std::filesystem::path records = folder / "records.bin";
        m_records_file = MappedFile::open(records, MappedFile::Access::random);
        const std::uint64_t need = std::max<std::uint64_t>(m_cell_begin.back(), 1) * sizeof(Record);
        if (m_records_file.size() != need + sizeof m_plan_id)
            throw Error(records.string() + ": " + std::to_string(m_records_file.size()) +
                        " bytes, the plan needs " + std::to_string(need + sizeof m_plan_id) +
                        " (records of another plan?)");
        std::uint64_t records_plan = 0;
        std::memcpy(&records_plan, m_records_file.data() + need, sizeof records_plan);
        if (records_plan != m_plan_id)
            throw Error(records.string() + ": written by another plan than " + path.string() +
                        " (a plan stage ran meanwhile: run this stage again)");
        m_part_views = {{reinterpret_cast<const Record*>(m_records_file.data()),
                         static_cast<std::size_t>(m_cell_begin.back())}};
        m_part_first = {0};
        m_cell_part.assign(m_cell_nodes.size(), 0);
        return stats;
    }

    static std::string part_name(std::uint32_t first, std::uint32_t last) {
        return "cells-" + std::to_string(first) + "-" + std::to_string(last) + ".bin";
    }

    /// Step 6 for cells [first, last) into FOLDER/cells-FIRST-LAST.bin (after load_plan).
    void build_part(const std::filesystem::path& folder, std::uint32_t first, std::uint32_t last,
                    PointBrickStats& stats) {
        if (first >= last || last > cell_count())
            throw Error("cells " + std::to_string(first) + ":" + std::to_string(last) +
                        " outside the plan's 0:" + std::to_string(cell_count()));
        AtomicFile f(folder / part_name(first, last));
        std::uint64_t at = 0;
        std::mutex writing;
        build(
            first, last, 0,
            [&](std::span<const std::byte> b) {
                const std::lock_guard<std::mutex> lock(writing);
                f.write(b.data(), b.size());
                at += b.size();
                return at - b.size();
            },
            stats);
        BlobWriter w;
        w.put(m_plan_id);
        w.put(first);
        w.put(last);
        for (std::uint32_t c = first; c < last; ++c) {
            const CellBricks& cb = m_cells[c];
            w.put(cb.payload);
            w.put(cb.payload_bytes);
            w.put_vector(cb.top_nodes);
            w.put_vector(cb.table);
            w.put_vector(cb.lod);
            w.put_vector(cb.sums);
            w.put_vector(cb.lod_table);
            w.put_vector(cb.lod_nodes);
            w.put_vector(cb.lod_discs);
        }
        w.put(stats);
        w.put(m_depth);
        w.put(m_top_depth);
        w.put(m_error);
        f.write(w.bytes().data(), w.bytes().size());
        const std::uint64_t footer[4] = {at, w.bytes().size(), pool::checksum(w.bytes()), k_cells_magic};
        f.write(footer, sizeof footer);
        f.commit();
    }

    /// Reads every FOLDER/cells-*.bin (after load_plan): they must cover the plan's cells once each.
    void load_parts(const std::filesystem::path& folder, PointBrickStats& stats) {
        m_cells.assign(cell_count(), CellBricks{});
        std::vector<std::uint32_t> owner(cell_count(), k_no_cell);
        std::vector<std::filesystem::path> paths;
        for (const auto& entry : std::filesystem::directory_iterator(folder)) {
            const std::string name = entry.path().filename().string();
            if (name.starts_with("cells-") && name.ends_with(".bin")) paths.push_back(entry.path());
        }
        std::sort(paths.begin(), paths.end());
        for (const std::filesystem::path& path : paths) {
            MappedFile file = MappedFile::open(path, MappedFile::Access::random);
            const std::span<const std::byte> all = bytes_of(file);
            std::uint64_t footer[4] = {0, 0, 0, 0};
            const auto corrupt = [&] {
                return Error(path.string() +
                             ": checksum mismatch: corrupt, truncated or not written by this prt-bricks");
            };
            if (all.size() < sizeof footer) throw corrupt();
            std::memcpy(footer, all.data() + all.size() - sizeof footer, sizeof footer);
            if (footer[3] != k_cells_magic || footer[0] > all.size() - sizeof footer ||
                footer[1] != all.size() - sizeof footer - footer[0])
                throw corrupt();
            const std::span<const std::byte> blob = all.subspan(footer[0], footer[1]);
            if (pool::checksum(blob) != footer[2]) throw corrupt();
            BlobReader r(blob, path.string());
            if (r.get<std::uint64_t>() != m_plan_id)
                throw Error(path.string() + ": built from another plan than " +
                            (folder / "plan.bin").string() + " (remove it and build its cells again)");
            const auto first = r.get<std::uint32_t>(), last = r.get<std::uint32_t>();
            if (first >= last || last > cell_count())
                throw Error(path.string() + ": cells " + std::to_string(first) + ":" + std::to_string(last) +
                            " outside the plan's 0:" + std::to_string(cell_count()) +
                            " (a part of another plan?)");
            const std::uint32_t part = std::uint32_t(m_parts.size());
            for (std::uint32_t c = first; c < last; ++c) {
                if (owner[c] != k_no_cell)
                    throw Error(path.string() + ": cell " + std::to_string(c) + " is also in " +
                                paths[owner[c]].filename().string());
                owner[c] = std::uint32_t(&path - paths.data());
                CellBricks& cb = m_cells[c];
                cb.part = part;
                cb.payload = r.get<std::uint64_t>();
                cb.payload_bytes = r.get<std::uint64_t>();
                cb.top_nodes = r.get_vector<std::uint32_t>();
                cb.table = r.get_vector<pool::BrickEntry>();
                cb.lod = r.get_vector<pool::LodSplat>();
                cb.sums = r.get_vector<LodSum>();
                cb.lod_table = r.get_vector<pool::BrickLod>();
                cb.lod_nodes = r.get_vector<std::uint32_t>();
                cb.lod_discs = r.get_vector<pool::CompressedSplat>();
                if (cb.payload > footer[0] || cb.payload_bytes > footer[0] - cb.payload) throw corrupt();
                for (const pool::BrickEntry& e : cb.table)
                    if (e.offset < cb.payload || e.offset - cb.payload > cb.payload_bytes ||
                        e.size > cb.payload_bytes - (e.offset - cb.payload))
                        throw corrupt();
            }
            const auto built = r.get<PointBrickStats>();
            m_depth = std::max(m_depth, r.get<std::uint32_t>());
            m_top_depth = std::max(m_top_depth, r.get<std::uint32_t>());
            m_error.merge(r.get<CodecError>());
            if (!r.done()) r.fail();
            add_cells(stats, built);
            m_parts.push_back(std::move(file));
        }
        for (std::uint32_t c = 0; c < cell_count(); ++c) {
            if (owner[c] != k_no_cell) continue;
            std::uint32_t e = c;
            while (e < cell_count() && owner[e] == k_no_cell) ++e;
            throw Error(folder.string() + ": cells " + std::to_string(c) + ":" + std::to_string(e) +
                        " are not built (prt-bricks --stage cells --cells " + std::to_string(c) + ":" +
                        std::to_string(e) + ")");
        }
    }

    /// Step 7 from the loaded parts.
    PointBricks merge(PointBrickStats& stats) {
        const double start = tool::now_seconds();
        // Each brick's own checksum (BrickEntry::checksum) is checked as it is copied into the pool
        // (PayloadSource): one pass over the parts finds a damaged payload and names its part.
        auto source = std::make_shared<PayloadSource>();
        source->parts = std::move(m_parts);
        PointBricks out = assemble(stats, std::move(source));
        stats.assemble_seconds = tool::now_seconds() - start;
        stats.seconds = stats.partition_seconds + stats.octree_seconds + stats.cull_seconds +
                        stats.brick_seconds + stats.payload_write_seconds + stats.assemble_seconds;
        return out;
    }

private:
    /// Unmaps the input's pages of points [b, e) when the input is a file mapping, so that the passes
    /// over a model larger than memory keep the resident set bounded (spill_file.h drop_pages).
    void drop_input(std::size_t b, std::size_t e) const {
        if (!m_params.input_mapped) return;
        drop_pages(m_positions.data() + b, (e - b) * sizeof(pool::Float3));
        drop_pages(m_normals.data() + b, (e - b) * sizeof(pool::Float3));
        if (m_params.radii_mapped) drop_pages(m_radii.data() + b, (e - b) * sizeof(float));
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
        const std::uint64_t capacity = cell_capacity(m_params);
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
        // The inner nodes' child boxes, once: the count and scatter passes classify every point at
        // each inner node it reaches (prepared once per point, prepare_build_splat).
        m_boxes.assign(m_nodes.size(), ChildBoxes{});
        for (std::size_t k = 0; k < m_nodes.size(); ++k)
            if (inner(std::uint32_t(k))) m_boxes[k] = child_boxes(m_root, m_nodes[k].at);
    }

    bool inner(std::uint32_t i) const { return m_nodes[i].cell == k_no_cell; }

    /// Point i prepared for classify(); false for a point the octree builder skips.
    bool prepare(std::size_t i, BuildSplat& s) const {
        return prepare_build_splat(m_positions[i], m_normals[i], m_radii[i], s);
    }

    /// Calls visit(cell) for each cell the prepared point's splat goes to, accumulating inner nodes'
    /// counts and radii (s.r, the point's radius) into `counts` / `sums` (per node) when given.
    template <class Visit>
    void classify(const BuildSplat& s, Visit&& visit, std::uint64_t* counts, double* sums) const {
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
            if (counts) ++counts[k], sums[k] += s.r;
            const std::uint8_t mask = child_overlap_mask(s, m_boxes[k], replicate);
            for (std::uint32_t c = 8; c-- > 0;)  // children in order, depth first
                if (mask >> c & 1u) stack[top++] = m_nodes[k].first + c;
        }
    }

    /// Calls visit(cell) for each cell point i's splat goes to, as classify() does, with its counts
    /// and radius sums; false for a point the octree builder skips. Most points are placed from their
    /// centre alone: where a cube around the centre that holds the splat's box
    /// (build_splat_box_bound) reaches no mid-plane on the way down, child_overlap_mask picks the
    /// centre's child at every node, so preparing the splat (its disk's box in double precision,
    /// thesis 3.4) and testing it are skipped (most of the count pass's time before).
    template <class Visit>
    bool place(std::size_t i, Visit&& visit, std::uint64_t* counts, double* sums) const {
        const pool::Float3 p = m_positions[i];
        const float r = m_radii[i];
        if (!octree_uses_point(p, m_normals[i], r)) return false;
        const double c[3] = {p.x, p.y, p.z};
        const bool replicate = m_params.octree.replicate;
        double h[3] = {0, 0, 0};
        if (replicate)
            for (int a = 0; a < 3; ++a) h[a] = build_splat_box_bound(c[a], r);
        std::uint32_t path[k_histogram_level + 1];
        std::uint32_t depth = 0, k = 0;
        while (inner(k)) {
            const double* mid = m_boxes[k].mid;
            unsigned child = 0;
            for (int a = 0; a < 3; ++a) {
                if (c[a] - h[a] <= mid[a] && c[a] + h[a] >= mid[a] && replicate) {  // the cube reaches it
                    BuildSplat s;
                    prepare(i, s);
                    classify(s, visit, counts, sums);
                    return true;
                }
                if (c[a] >= mid[a]) child |= 1u << a;  // the half-open child of the centre
            }
            path[depth++] = k;
            k = m_nodes[k].first + child;
        }
        if (counts)
            for (std::uint32_t d = 0; d < depth; ++d) ++counts[path[d]], sums[path[d]] += r;
        visit(m_nodes[k].cell);
        return true;
    }

    // -- 4 ----------------------------------------------------------------------------------------
    void count() {
        const std::size_t nodes = m_nodes.size();
        const std::size_t cells = m_cell_nodes.size();
        std::vector<std::vector<std::uint64_t>> counts(m_threads, std::vector<std::uint64_t>(nodes, 0));
        std::vector<std::vector<double>> sums(m_threads, std::vector<double>(nodes, 0.0));
        std::atomic<std::uint64_t> done{0};
        // Each point's cell, when it has one only (most points: 1.01 records a point on the 500M
        // room), for the scatter, which then neither prepares nor classifies it again: 4 bytes a
        // point, kept where they fit in a quarter of the memory budget.
        if (m_positions.size() * sizeof(std::uint32_t) <= m_params.memory / 4)
            m_point_cell = Buffer<std::uint32_t>(m_positions.size());
        std::uint32_t* point_cell = m_point_cell.size() ? m_point_cell.data() : nullptr;
        parallel_chunks(m_positions.size(), k_chunk, m_threads,
                        [&](std::size_t b, std::size_t e, unsigned w) {
                            std::uint64_t* row = m_cell_count.data() + (b / k_chunk) * cells;
                            for (std::size_t i = b; i < e; ++i) {
                                std::uint32_t only = k_no_cell;
                                place(
                                    i,
                                    [&](std::uint32_t cell) {
                                        ++row[cell];
                                        only = only == k_no_cell ? cell : k_several_cells;
                                    },
                                    counts[w].data(), sums[w].data());
                                if (point_cell) point_cell[i] = only;
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
    void scatter(const std::filesystem::path& records_file) {
        const std::size_t cells = m_cell_nodes.size();
        const std::uint64_t records = m_cell_begin[cells];
        // The records go to parts of whole cells, a file each, about four per worker: a write holds
        // its file's lock (the inode's) for its whole copy, so into one file the workers' writes
        // queue. The staged build writes its one named file.
        const std::uint64_t parts =
            records_file.empty() ? std::min<std::uint64_t>(cells, 4 * std::uint64_t(m_threads)) : 1;
        m_part_first.assign(1, 0);
        m_cell_part.assign(cells, 0);
        for (std::size_t c = 0; c < cells; ++c) {
            const std::uint64_t begin = m_cell_begin[c];
            if (m_part_first.size() < parts && begin > m_part_first.back() &&
                begin * parts >= m_part_first.size() * records)
                m_part_first.push_back(begin);
            m_cell_part[c] = std::uint32_t(m_part_first.size() - 1);
        }
        m_record_parts.clear();
        m_part_views.clear();
        for (std::size_t k = 0; k < m_part_first.size(); ++k) {
            const std::uint64_t n =
                (k + 1 < m_part_first.size() ? m_part_first[k + 1] : records) - m_part_first[k];
            const std::uint64_t bytes = std::max<std::uint64_t>(n, 1) * sizeof(Record);
            if (records_file.empty()) {
                m_record_parts.emplace_back(m_params.spill_folder, bytes, "the partitioned points");
            } else {
                m_record_parts.push_back(
                    SpillFile::named(records_file, bytes + sizeof m_plan_id, "the partitioned points"));
                std::memcpy(m_record_parts.back().data() + bytes, &m_plan_id, sizeof m_plan_id);
            }
            m_part_views.push_back(m_record_parts.back().as<const Record>().first(n));
        }
        std::atomic<std::uint64_t> done{0};
        // Each chunk's records are sorted by cell in a buffer of the worker's (the count pass gave
        // the chunk's count per cell) and written with one pwrite per cell: through the mapping, every
        // page of the spill file cost the writing thread a fault (the 20M room's scatter 2.05 s on the
        // dev VM's 2 cores, of which the count pass's same classification is 0.65 s).
        std::vector<std::vector<Record>> buffers(m_threads);
        std::vector<std::vector<std::uint64_t>> cursors(m_threads, std::vector<std::uint64_t>(cells));
        parallel_chunks(
            m_positions.size(), k_chunk, m_threads, [&](std::size_t b, std::size_t e, unsigned w) {
                const std::size_t row = (b / k_chunk) * cells;
                const std::uint64_t* count = m_cell_count.data() + row;
                std::vector<std::uint64_t>& at = cursors[w];
                std::uint64_t total = 0;
                for (std::size_t c = 0; c < cells; ++c) at[c] = total, total += count[c];
                std::vector<Record>& buffer = buffers[w];
                if (buffer.size() < total) buffer.resize(total);
                const std::uint32_t* point_cell = m_point_cell.size() ? m_point_cell.data() : nullptr;
                for (std::size_t i = b; i < e; ++i) {
                    const std::uint32_t only = point_cell ? point_cell[i] : k_several_cells;
                    if (only == k_no_cell) continue;  // not usable, or in no cell
                    const Record r{m_positions[i], m_normals[i], m_radii[i],
                                   m_colors.empty() ? pool::Rgba8{255, 255, 255, 255} : m_colors[i]};
                    if (only != k_several_cells) {
                        buffer[at[only]++] = r;
                        continue;
                    }
                    place(
                        i, [&](std::uint32_t cell) { buffer[at[cell]++] = r; }, nullptr, nullptr);
                }
                drop_input(b, e);
                for (std::size_t c = 0; c < cells; ++c)
                    if (count[c] > 0) {
                        const std::uint32_t rp = m_cell_part[c];
                        m_record_parts[rp].write_at((m_slot[row + c] - m_part_first[rp]) * sizeof(Record),
                                                    buffer.data() + (at[c] - count[c]),
                                                    count[c] * sizeof(Record));
                    }
                const std::uint64_t d = done.fetch_add(e - b) + (e - b);
                if (w == 0) report("partitioning points", m_positions.size() + d, 2 * m_positions.size());
            });
        std::vector<std::uint64_t>().swap(m_slot);
        std::vector<std::uint64_t>().swap(m_cell_count);
        m_point_cell = Buffer<std::uint32_t>();
    }

    // -- 6 ----------------------------------------------------------------------------------------
    /// One cell's bricks, numbered within the cell, with its payload in m_payloads.
    struct CellBricks {
        std::uint32_t part = 0;                        ///< the payload file (staged build)
        std::uint64_t payload = 0, payload_bytes = 0;  ///< where, in it
        std::vector<std::uint32_t> top_nodes;
        std::vector<pool::BrickEntry> table;  // offset: into m_payloads
        std::vector<pool::LodSplat> lod;
        std::vector<LodSum> sums;
        std::vector<pool::BrickLod> lod_table;  // first: into lod_nodes
        std::vector<std::uint32_t> lod_nodes;
        std::vector<pool::CompressedSplat> lod_discs;
    };

    /// One cell (step 6): its subtree built, culled and cut; the payload handed to `append`.
    void build_cell(std::uint32_t c, std::uint32_t part,
                    const std::function<std::uint64_t(std::span<const std::byte>)>& append,
                    PointBrickStats& stats, unsigned threads) {
        const std::uint64_t b = m_cell_begin[c], e = m_cell_begin[c + 1];
        if (b == e) return;
        const NodeCell at = m_nodes[m_cell_nodes[c]].at;
        const std::uint32_t rp = m_cell_part[c];
        const std::span<const Record> recs = m_part_views[rp].subspan(b - m_part_first[rp], e - b);
        std::vector<pool::Float3> positions(recs.size()), normals(recs.size());
        std::vector<float> radii(recs.size());
        std::vector<pool::Rgba8> colors(m_has_colors ? recs.size() : 0);
        for (std::size_t k = 0; k < recs.size(); ++k) {
            positions[k] = recs[k].position;
            normals[k] = recs[k].normal;
            radii[k] = recs[k].radius;
            if (!colors.empty()) colors[k] = recs[k].color;
        }
        drop_pages(recs.data(), recs.size_bytes());
        OctreeParams op = m_params.octree;
        op.threads = threads;
        op.progress = nullptr;
        op.backend = m_octree_backend;
        SplatOctree octree;
        std::uint64_t stored = 0;
        double octree_seconds = 0, cull_seconds = 0;
        bool on_device = false;
        if (m_params.cull) {
            CullParams cp = m_params.culling;
            cp.threads = threads;
            cp.progress = nullptr;
            CulledCell culled = build_culled_cell(positions, normals, radii, m_root, at, op, cp);
            octree = std::move(culled.octree);
            stored = culled.stored;
            octree_seconds = culled.build_seconds;
            cull_seconds = culled.cull_seconds;
            on_device = culled.on_device;
        } else {
            const double t0 = tool::now_seconds();
            octree = build_octree_cell(positions, normals, radii, m_root, at, op);
            stored = octree.splats.size();
            octree_seconds = tool::now_seconds() - t0;
        }
        std::vector<pool::Float3>().swap(positions);
        std::vector<pool::Float3>().swap(normals);
        std::vector<float>().swap(radii);
        const pool::SplatOctreeSections sections{octree.info, octree.nodes, octree.leaf_info, octree.splats};
        const double t2 = tool::now_seconds();
        BrickParams bp = m_params.bricks;
        bp.threads = threads;
        bp.progress = nullptr;
        BrickPart bricks = build_brick_part(sections, colors, bp, at);
        const double t3 = tool::now_seconds();
        // The payload written before the lock: `append` takes concurrent calls (a cell's payload is
        // about 5 MB; written under the lock, the 500M room's 1579 cells waited for each other's).
        const std::uint64_t base = append(bricks.bricks.data);
        const double t4 = tool::now_seconds();
        // The cell's results into the shared state (cells build concurrently:
        // PointBrickParams::cell_workers).
        const std::lock_guard<std::mutex> lock(m_mutex);
        for (pool::BrickEntry& entry : bricks.bricks.table) entry.offset += base;
        m_cells[c] = CellBricks{part,
                                base,
                                bricks.bricks.data.size(),
                                std::move(bricks.bricks.top_nodes),
                                std::move(bricks.bricks.table),
                                std::move(bricks.bricks.lod),
                                std::move(bricks.sums),
                                std::move(bricks.bricks.lod_table),
                                std::move(bricks.bricks.lod_nodes),
                                std::move(bricks.bricks.lod_discs)};
        m_error.merge(bricks.error);
        m_top_depth = std::max(m_top_depth, bricks.top_depth);
        m_depth = std::max(m_depth, octree.info.depth);
        PointBrickStats cell;
        cell.cells = 1;
        cell.partition_depth = at.level;
        cell.max_cell_points = cell.cell_records = e - b;
        cell.stored_splats = stored;
        cell.culled_splats = sections.splats.size();
        cell.octree_seconds = octree_seconds;
        cell.cull_seconds = cull_seconds;
        cell.cells_culled_on_device = on_device ? 1 : 0;
        cell.brick_seconds = t3 - t2;
        cell.payload_write_seconds = t4 - t3;
        add_cells(stats, cell);
    }

    // -- 7 ----------------------------------------------------------------------------------------
    /// The top tree, table and LOD; the payloads are copied from `source` (the cells' payload files)
    /// when the pool is written (PointBricks::data).
    PointBricks assemble(PointBrickStats& stats, std::shared_ptr<PayloadSource> source) {
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
            offset += pool::brick_padded_size(e.size);
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
        source->bricks.resize(brick_src.size());
        for (std::size_t b = 0; b < brick_src.size(); ++b) {
            const CellBricks& cb = m_cells[brick_src[b].first];
            const pool::BrickEntry& src = cb.table[brick_src[b].second];
            source->bricks[b] = PayloadSource::Brick{cb.part, src.offset, src.size, src.checksum};
        }
        source->progress = m_params.progress;
        out.data = [source](const pool::PoolWriter::ByteSink& sink) { source->generate(sink); };
        out.data_bytes = offset;
        std::uint32_t top_depth = m_top_depth;
        for (const PartNode& p : m_nodes) top_depth = std::max(top_depth, p.at.level);
        pool::OctreeInfo info = m_root;
        info.depth = std::max(m_depth, top_depth);  // an empty cell is a leaf at its level
        info.unique_splats = stats.points;
        info.flags = (m_params.octree.replicate ? pool::k_octree_replicated : 0u) |
                     (m_params.cull ? pool::k_octree_culled : 0u);
        stats.bricks = finish_bricks(br, sums, info, top_depth, m_params.bricks, m_has_colors);
        stats.bricks.data_bytes = offset;
        stats.bricks.error = m_error;
        return out;
    }

    std::span<const pool::Float3> m_positions, m_normals;
    std::span<const float> m_radii;
    std::span<const pool::Rgba8> m_colors;
    bool m_has_colors;
    const PointBrickParams& m_params;
    unsigned m_threads;
    std::string m_octree_backend;  // the cells' octrees: "cpu" or "cuda" (resolved once)
    pool::OctreeInfo m_root{};
    std::size_t m_chunks = 0;
    std::vector<PartNode> m_nodes;
    std::vector<std::uint32_t> m_cell_nodes;  // cell -> partition node
    std::vector<ChildBoxes> m_boxes;          // partition node -> its children's boxes (inner nodes)
    std::vector<std::uint64_t> m_cell_count;  // [chunk][cell]
    std::vector<std::uint64_t> m_slot;        // [chunk][cell]: next record index
    Buffer<std::uint32_t> m_point_cell;       // per point: its only cell, k_several_cells or k_no_cell
    std::vector<std::uint64_t> m_cell_begin;  // cell -> first record
    // The records (step 5) in parts of whole cells: cell c's are m_part_views[m_cell_part[c]] from
    // record m_cell_begin[c] - m_part_first[part]. Spill files of the build in this process
    // (m_record_parts), else the staged build's one records file.
    std::vector<SpillFile> m_record_parts;
    std::shared_ptr<SpillReleaser> m_releaser;  // run(): closes each part of the records once built
    std::vector<std::span<const Record>> m_part_views;
    std::vector<std::uint64_t> m_part_first;  // part -> its first record
    std::vector<std::uint32_t> m_cell_part;   // cell -> its part
    MappedFile m_records_file;
    std::vector<MappedFile> m_parts;  // the staged build's part files, by CellBricks::part
    std::mutex m_mutex;               // build_cell's shared results, the payload file, progress
    AppendFile m_payloads;
    std::vector<CellBricks> m_cells;
    std::uint32_t m_depth = 0, m_top_depth = 0;
    /// The staged build's plan: a random id in plan.bin, at the end of records.bin and in every part,
    /// so that no stage mixes files of two plans (a re-plan while cells are still being built).
    std::uint64_t m_plan_id = 0;
    CodecError m_error;
};

}  // namespace

std::uint32_t plan_brick_cells(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                               std::span<const float> radii, std::span<const pool::Rgba8> colors,
                               const PointBrickParams& params, const std::filesystem::path& folder,
                               PointBrickStats* stats_out) {
    PointBrickStats stats;
    Partitioner partitioner(positions, normals, radii, colors, params);
    // The records go to a temporary file renamed over records.bin once the partition is complete: a
    // partition that fails leaves the folder's plan, records and parts as they were, and a cell
    // builder still reading the old records (mapped) keeps them, where truncating the file in place
    // would have faulted its reads (its part is then refused by the plan id).
    AtomicFile records(folder / "records.bin");
    partitioner.new_plan_id();
    partitioner.plan(stats, records.temporary());
    std::filesystem::remove(folder / "plan.bin");  // a folder holds one plan: the old one goes
    for (const auto& entry : std::filesystem::directory_iterator(folder))
        if (const std::string name = entry.path().filename().string();
            name.starts_with("cells-") && name.ends_with(".bin"))
            std::filesystem::remove(entry.path());
    records.commit();
    partitioner.save_plan(folder, stats);
    // Reported, not saved: the cells count their own records as they are built.
    stats.cell_records = partitioner.record_count();
    if (stats_out) *stats_out = stats;
    return partitioner.cell_count();
}

std::uint32_t planned_brick_cells(const std::filesystem::path& folder, const PointBrickParams& params) {
    Partitioner partitioner({}, {}, {}, {}, params);
    partitioner.load_plan(folder);
    return partitioner.cell_count();
}

void build_brick_cells(const std::filesystem::path& folder, const PointBrickParams& params,
                       std::uint32_t first, std::uint32_t last, PointBrickStats* stats_out) {
    Partitioner partitioner({}, {}, {}, {}, params);
    PointBrickStats stats = partitioner.load_plan(folder);
    stats.partition_seconds = 0;
    const double start = tool::now_seconds();
    partitioner.build_part(folder, first, last, stats);
    stats.seconds = tool::now_seconds() - start;
    if (stats_out) *stats_out = stats;
}

PointBricks merge_brick_cells(const std::filesystem::path& folder, const PointBrickParams& params,
                              PointBrickStats* stats_out) {
    Partitioner partitioner({}, {}, {}, {}, params);
    PointBrickStats stats = partitioner.load_plan(folder);
    partitioner.load_parts(folder, stats);
    PointBricks out = partitioner.merge(stats);
    stats.bricks.seconds = stats.seconds;
    if (stats_out) *stats_out = stats;
    return out;
}

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
