// PointRT prt-photons: photon shooting on the CPU (or through prt_photons_cuda) and the caustic
// octree (thesis 5.4).
#include "photons.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <mutex>

#include "buffer.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"

#if defined(PRT_HAVE_CUDA)
#include "prt/cuda/device.h"
#include "prt/cuda/photons_cuda.h"
#endif

namespace prt::photons {

namespace {

constexpr double k_pi = 3.14159265358979323846;

void add_tally(PhotonTally& t, const PhotonTallyF& f) {
    const core::Vec3* src[6] = {&f.emitted, &f.direct, &f.deposited, &f.absorbed, &f.escaped, &f.truncated};
    double* dst[6] = {t.emitted, t.direct, t.deposited, t.absorbed, t.escaped, t.truncated};
    for (int k = 0; k < 6; ++k) {
        dst[k][0] += src[k]->x;
        dst[k][1] += src[k]->y;
        dst[k][2] += src[k]->z;
    }
    t.deposits += f.deposits;
    t.specular_hits += f.specular_hits;
    t.rays += f.rays;
}

void add_tally(PhotonTally& t, const PhotonTally& o) {
    for (int a = 0; a < 3; ++a) {
        t.emitted[a] += o.emitted[a];
        t.direct[a] += o.direct[a];
        t.deposited[a] += o.deposited[a];
        t.absorbed[a] += o.absorbed[a];
        t.escaped[a] += o.escaped[a];
        t.truncated[a] += o.truncated[a];
    }
    t.deposits += o.deposits;
    t.specular_hits += o.specular_hits;
    t.rays += o.rays;
}

/// v where mask is all ones, +0 where it is zero (a bit mask: compiles to no branch).
inline float masked(float v, std::uint32_t mask) {
    return std::bit_cast<float>(std::bit_cast<std::uint32_t>(v) & mask);
}

float luminance(const float c[3]) {
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

/// A deposit as the density loop reads it (thesis 5.4.2): its offset inside its cell (floats keep
/// full precision there at any depth), flux and luminance-weighted normal.
struct Packed {
    float frac[3];
    float flux[3];
    float normal[3];  ///< luminance x normal
    float lum;
};

/// A corner's running sums of eq. 5.1-5.2 (before the normalisation).
struct CornerSum {
    float value[3];
    float normal[3];
    float weight;  ///< sum of kernel x luminance: |normal| / weight says how one-sided it is
};

/// One corner a cell reaches: its sums and the cell's offset from it (cell - corner, in edges).
struct Lane {
    std::uint32_t corner;
    float offset[3];
};

constexpr std::size_t k_lanes = 8;

/// Adds the kernel-weighted deposits d[0..n) of one cell to the sums of up to 8 corners, in the
/// deposits' order: per corner, sum += (1 - r^2 / g^2) x quantity for each deposit with r < g.
/// The lanes are independent (the compiler vectorises them); a deposit outside g adds +0 to every
/// sum (a bit mask: no branch to mispredict), which leaves the sum as it was since a sum is never
/// -0, so each corner's sums are bit for bit those of adding only the deposits within g.
void accumulate_lanes(const Lane* lanes, std::size_t count, const Packed* d, std::uint32_t n, float inv_g2,
                      CornerSum* sums) {
    float ox[k_lanes], oy[k_lanes], oz[k_lanes];
    float v0[k_lanes], v1[k_lanes], v2[k_lanes], n0[k_lanes], n1[k_lanes], n2[k_lanes], wt[k_lanes];
    for (std::size_t l = 0; l < k_lanes; ++l) {
        const bool real = l < count;
        // A padding lane sits far away (r > g for every deposit) and is not stored back.
        ox[l] = real ? lanes[l].offset[0] : 1e6f;
        oy[l] = real ? lanes[l].offset[1] : 0.0f;
        oz[l] = real ? lanes[l].offset[2] : 0.0f;
        const CornerSum s = real ? sums[lanes[l].corner] : CornerSum{};
        v0[l] = s.value[0];
        v1[l] = s.value[1];
        v2[l] = s.value[2];
        n0[l] = s.normal[0];
        n1[l] = s.normal[1];
        n2[l] = s.normal[2];
        wt[l] = s.weight;
    }
    for (std::uint32_t j = 0; j < n; ++j) {
        const Packed& p = d[j];
        for (std::size_t l = 0; l < k_lanes; ++l) {
            const float dx = ox[l] + p.frac[0], dy = oy[l] + p.frac[1], dz = oz[l] + p.frac[2];
            const float r2 = (dx * dx + dy * dy + dz * dz) * inv_g2;
            const std::uint32_t in = 0u - static_cast<std::uint32_t>(r2 < 1.0f);
            const float w = 1.0f - r2;
            v0[l] += masked(w * p.flux[0], in);
            n0[l] += masked(w * p.normal[0], in);
            v1[l] += masked(w * p.flux[1], in);
            n1[l] += masked(w * p.normal[1], in);
            v2[l] += masked(w * p.flux[2], in);
            n2[l] += masked(w * p.normal[2], in);
            wt[l] += masked(w * p.lum, in);
        }
    }
    for (std::size_t l = 0; l < count; ++l) {
        CornerSum& s = sums[lanes[l].corner];
        s.value[0] = v0[l];
        s.value[1] = v1[l];
        s.value[2] = v2[l];
        s.normal[0] = n0[l];
        s.normal[1] = n1[l];
        s.normal[2] = n2[l];
        s.weight = wt[l];
    }
}

}  // namespace

float solid_angle_norm(std::uint32_t face_res) {
    double sum = 0.0;
    const double h = 2.0 / face_res;
    for (std::uint32_t y = 0; y < face_res; ++y) {
        const double t = -1.0 + (y + 0.5) * h;
        for (std::uint32_t x = 0; x < face_res; ++x) {
            const double s = -1.0 + (x + 0.5) * h;
            const double q = 1.0 + s * s + t * t;
            sum += h * h / (q * std::sqrt(q));
        }
    }
    return static_cast<float>(4.0 * k_pi / (6.0 * sum));
}

std::string resolve_backend(const std::string& requested, std::string* why) {
    if (requested == "cpu") return "cpu";
#if defined(PRT_HAVE_CUDA)
    std::string reason;
    if (cuda::photons_device_available(&reason)) return "cuda";
    if (requested == "cuda") throw Error("--backend cuda: " + reason);
    if (why) *why = reason;
    return "cpu";
#else
    if (requested == "cuda") throw Error("--backend cuda: this build has no CUDA backend");
    if (why) *why = "this build has no CUDA backend";
    return "cpu";
#endif
}

std::future<void> warm_up(const std::string& backend) {
#if defined(PRT_HAVE_CUDA)
    if (backend == "cuda") return std::async(std::launch::async, [] { cuda::warm_up_device(); });
#endif
    std::promise<void> ready;
    ready.set_value();
    return ready.get_future();
}

ShootResult shoot_photons(const core::SceneView& scene, const ShootOptions& options,
                          const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    ShootResult result;
    ShootParams params = options.params;
    params.solid_angle_norm = solid_angle_norm(params.face_res);
    const std::uint64_t per_light = photons_per_light(params);
    const std::uint64_t total = per_light * core::photon_light_count(scene);
    result.tally.photons = total;
    const std::string backend = resolve_backend(options.backend);
    const double start = tool::now_seconds();
    if (backend == "cuda") {
#if defined(PRT_HAVE_CUDA)
        cuda::PhotonsCudaResult r = cuda::shoot_photons_cuda(scene, params, progress);
        result.deposits = std::move(r.deposits);
        add_tally(result.tally, r.tally);
        result.tally.photons = total;
        result.backend = r.device;
        result.kernel_seconds = r.kernel_seconds;
        result.setup_seconds = r.setup_seconds;
#endif
    } else {
        const unsigned threads = resolve_threads(options.threads);
        // Deposits and tallies per chunk of photons, joined in photon order: the map is the same
        // bytes whatever the thread count and however the chunks fall to the threads.
        constexpr std::size_t k_chunk = 1 << 14;
        const std::size_t chunks = (total + k_chunk - 1) / k_chunk;
        std::vector<std::vector<PhotonDeposit>> per_chunk(chunks);
        std::vector<PhotonTally> tallies(chunks);
        std::atomic<std::uint64_t> done{0};
        parallel_chunks(total, k_chunk, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {
            PhotonTallyF f;
            std::vector<PhotonDeposit>& out = per_chunk[begin / k_chunk];
            PhotonTally& tally = tallies[begin / k_chunk];
            for (std::size_t g = begin; g < end; ++g) {
                const std::uint32_t light = static_cast<std::uint32_t>(g / per_light);
                trace_photon(scene, params, light, g - light * per_light, f,
                             [&](const PhotonDeposit& d) { out.push_back(d); });
                // Float tallies stay exact enough over a few thousand photons; flush
                // often.
                if (((g - begin) & 1023u) == 1023u) {
                    add_tally(tally, f);
                    f = PhotonTallyF{};
                }
            }
            add_tally(tally, f);
            const std::uint64_t d = done.fetch_add(end - begin) + (end - begin);
            if (worker == 0 && progress) progress(d, total);
        });
        std::size_t count = 0;
        for (const auto& c : per_chunk) count += c.size();
        result.deposits.reserve(count);
        for (std::size_t c = 0; c < chunks; ++c) {
            result.deposits.insert(result.deposits.end(), per_chunk[c].begin(), per_chunk[c].end());
            std::vector<PhotonDeposit>().swap(per_chunk[c]);
            add_tally(result.tally, tallies[c]);
        }
        result.backend = "cpu (" + std::to_string(threads) + " threads)";
    }
    result.seconds = tool::now_seconds() - start;
    if (backend != "cuda") result.kernel_seconds = result.seconds;
    return result;
}

namespace {

/// The deposits in cell order, as offsets inside their cell (floats keep full precision there at
/// any depth) with their flux and luminance-weighted normal: the density loop reads them
/// sequentially, cell by cell.
pre::Buffer<Packed> pack_deposits(std::span<const PhotonDeposit> deposits, const CellBins& bins,
                                  unsigned threads) {
    pre::Buffer<Packed> packed(deposits.size());  // first touched by the parallel fill
    parallel_chunks(bins.cell_keys.size(), 4096, threads, [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t c = begin; c < end; ++c) {
            std::uint32_t cell[3];
            pre::demorton3(bins.cell_keys[c], cell[0], cell[1], cell[2]);
            for (std::uint32_t j = bins.cell_begin[c]; j < bins.cell_begin[c + 1]; ++j) {
                // The deposits are read in random order: ask for them early.
                if (j + 16 < deposits.size()) {
                    const char* ahead = reinterpret_cast<const char*>(&deposits[bins.order[j + 16]]);
                    __builtin_prefetch(ahead);
                    __builtin_prefetch(ahead + sizeof(PhotonDeposit) - 1);
                }
                const PhotonDeposit& d = deposits[bins.order[j]];
                double g[3];
                bins.grid(d.position, g);
                Packed& p = packed[j];
                p.lum = luminance(d.flux);
                for (int a = 0; a < 3; ++a) {
                    p.frac[a] = static_cast<float>(g[a] - cell[a]);
                    p.flux[a] = d.flux[a];
                    p.normal[a] = p.lum * d.normal[a];
                }
            }
        }
    });
    return packed;
}

/// The blocks of S^3 leaf cells: S = 16 cells a side (the whole lattice when shallower). Block L's
/// task covers leaves L*S .. L*S+S-1 and corners L*S .. L*S+S (per axis), so it needs the occupied
/// cells L*S-r .. L*S+S+r-1 (r = ceil(g)): the cells of blocks within `halo` of L.
struct Blocks {
    std::uint32_t s;  ///< S = 2^s
    std::int64_t S;
    std::uint32_t sbits;      ///< 3s: a cell's key is its block's key << sbits | its local key
    std::int64_t reach;       ///< r = ceil(g), in cells
    std::int64_t cells;       ///< leaf cells a side (2^depth)
    std::int64_t halo;        ///< blocks a task reaches each way
    std::int64_t last_block;  ///< corners reach coordinate `cells`
    std::int64_t last_cell_block;
    std::int64_t W;  ///< the dense cell grid's side
    std::int64_t C;  ///< the dense corner grid's side

    Blocks(std::uint32_t depth, double ge)
        : s(std::min<std::uint32_t>(depth, 4)),
          S(std::int64_t{1} << s),
          sbits(3 * s),
          reach(static_cast<std::int64_t>(std::ceil(ge))),
          cells(std::int64_t{1} << depth),
          halo((S + reach - 1) / S),
          last_block(cells >> s),
          last_cell_block((cells - 1) >> s),
          W(S + 2 * reach),
          C(S + 1) {}
};

/// The tasks: the blocks within `halo` of an occupied block, sorted and unique (a few thousand keys).
std::vector<std::uint64_t> block_tasks(const CellBins& bins, const Blocks& bk, std::uint32_t depth,
                                       unsigned threads) {
    auto starts = [&](std::size_t c) {
        return c == 0 || (bins.cell_keys[c] >> bk.sbits) != (bins.cell_keys[c - 1] >> bk.sbits);
    };
    std::vector<std::uint64_t> occupied(
        parallel_select(bins.cell_keys.size(), threads, starts, [](std::size_t, std::size_t) {}));
    parallel_select(bins.cell_keys.size(), threads, starts,
                    [&](std::size_t rank, std::size_t c) { occupied[rank] = bins.cell_keys[c] >> bk.sbits; });
    std::vector<std::uint64_t> tasks;
    for (std::uint64_t b : occupied) {
        std::uint32_t bc[3];
        pre::demorton3(b, bc[0], bc[1], bc[2]);
        std::int64_t lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::max<std::int64_t>(0, std::int64_t{bc[a]} - bk.halo);
            hi[a] = std::min<std::int64_t>(bk.last_block, std::int64_t{bc[a]} + bk.halo);
        }
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
                    tasks.push_back(pre::morton3(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                                 static_cast<std::uint32_t>(z)));
    }
    gi::sort_unique(tasks, 3 * (depth - bk.s + 1), threads);
    return tasks;
}

/// What one task wrote, in its worker's arrays.
struct TaskOut {
    unsigned worker = 0;
    std::size_t corner_begin = 0, corner_count = 0;  ///< into the worker's corner values
    std::size_t leaf_begin = 0, leaf_count = 0;      ///< into the worker's leaves
};

/// One worker's results and scratch.
struct WorkerOut {
    std::vector<float> corner_values;  ///< 3 per corner
    std::vector<std::uint64_t> leaf_keys;
    std::vector<pool::GiLeaf> leaves;  ///< corner[c]: index into the task's corners (or missing)
    float max_value = 0.0f;            ///< largest finite corner value
    // Scratch: the dense grids are left all-missing after each task.
    std::vector<std::uint32_t> grid, corner_at, grid_used;
    std::vector<std::int64_t> corner_pos;
    std::vector<CornerSum> sums;
    std::vector<Lane> lanes;
    std::vector<std::uint64_t> leaf_bits;
    std::vector<std::uint8_t> row_used;  ///< per (z, y) row of the cell grid: any cell there
};

constexpr std::uint32_t k_missing = KeyMap::k_missing;

/// thesis 5.4.2, eq. 5.1-5.2 for one block: its corners, their density estimates and its leaves.
class BlockGather {
public:
    BlockGather(const CellBins& bins, const pre::Buffer<Packed>& packed, const Blocks& bk, float norm,
                float inv_g2)
        : m_bins(bins), m_packed(packed), m_bk(bk), m_norm(norm), m_inv_g2(inv_g2) {}

    /// The block of key `task`: appends its corner values and leaves to `out`, says where in `to`.
    void run(std::uint64_t task, WorkerOut& out, TaskOut& to) const {
        if (out.grid.empty()) {
            out.grid.assign(static_cast<std::size_t>(m_bk.W * m_bk.W * m_bk.W), k_missing);
            out.corner_at.assign(static_cast<std::size_t>(m_bk.C * m_bk.C * m_bk.C), k_missing);
            out.row_used.assign(static_cast<std::size_t>(m_bk.W * m_bk.W), 0);
            out.leaf_bits.assign((std::size_t{1} << m_bk.sbits) / 64 + 1, 0);
        }
        to.corner_begin = out.corner_values.size() / 3;
        to.leaf_begin = out.leaves.size();
        std::uint32_t bl[3];
        pre::demorton3(task, bl[0], bl[1], bl[2]);
        Range r;
        for (int a = 0; a < 3; ++a) {
            r.o[a] = std::int64_t{bl[a]} * m_bk.S;
            r.g0[a] = r.o[a] - m_bk.reach;
            r.clo[a] = std::max<std::int64_t>(0, r.o[a] - m_bk.reach);
            r.chi[a] = std::min<std::int64_t>(m_bk.cells - 1, r.o[a] + m_bk.S + m_bk.reach - 1);
        }
        place_cells(r, out);
        estimate(r, out);
        mark_leaves(r, out);
        emit_leaves(task, out);
        for (std::uint32_t at : out.grid_used) {
            out.grid[at] = k_missing;
            out.row_used[at / m_bk.W] = 0;
        }
        for (std::int64_t ca : out.corner_pos) out.corner_at[static_cast<std::size_t>(ca)] = k_missing;
        to.corner_count = out.corner_pos.size();
        to.leaf_count = out.leaves.size() - to.leaf_begin;
    }

private:
    /// A task's block origin o, its dense grid's origin g0 and the cells in reach clo..chi.
    struct Range {
        std::int64_t o[3], g0[3], clo[3], chi[3];
    };

    /// The corners of cell c in the block: c-r+1 .. c+r, within 0..cells.
    void cell_corners(const Range& r, const std::int64_t c[3], std::int64_t lo[3], std::int64_t hi[3]) const {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::max<std::int64_t>(c[a] - m_bk.reach + 1, r.o[a]);
            hi[a] = std::min<std::int64_t>({c[a] + m_bk.reach, r.o[a] + m_bk.S, m_bk.cells});
        }
    }

    /// The occupied cells in reach (the blocks covering clo..chi, cell by cell) into the dense
    /// grid, and the corners they reach into corner_at / corner_pos.
    void place_cells(const Range& r, WorkerOut& out) const {
        const std::int64_t W = m_bk.W, C = m_bk.C;
        const std::uint32_t s = m_bk.s;
        out.grid_used.clear();
        out.corner_pos.clear();
        for (std::int64_t bz = r.clo[2] >> s; bz <= (r.chi[2] >> s); ++bz)
            for (std::int64_t by = r.clo[1] >> s; by <= (r.chi[1] >> s); ++by)
                for (std::int64_t bx = r.clo[0] >> s; bx <= (r.chi[0] >> s); ++bx) {
                    if (bx > m_bk.last_cell_block || by > m_bk.last_cell_block || bz > m_bk.last_cell_block)
                        continue;
                    const std::uint64_t prefix =
                        pre::morton3(static_cast<std::uint32_t>(bx), static_cast<std::uint32_t>(by),
                                     static_cast<std::uint32_t>(bz));
                    const auto& keys = m_bins.cell_keys;
                    const auto first = std::lower_bound(keys.begin(), keys.end(), prefix << m_bk.sbits);
                    const auto last = std::lower_bound(first, keys.end(), (prefix + 1) << m_bk.sbits);
                    for (auto it = first; it != last; ++it) {
                        std::uint32_t cu[3];
                        pre::demorton3(*it, cu[0], cu[1], cu[2]);
                        const std::int64_t c[3] = {cu[0], cu[1], cu[2]};
                        bool inside = true;
                        for (int a = 0; a < 3; ++a) inside = inside && c[a] >= r.clo[a] && c[a] <= r.chi[a];
                        if (!inside) continue;
                        const std::uint32_t at = static_cast<std::uint32_t>(
                            ((c[2] - r.g0[2]) * W + (c[1] - r.g0[1])) * W + (c[0] - r.g0[0]));
                        out.grid[at] = static_cast<std::uint32_t>(it - keys.begin());
                        out.grid_used.push_back(at);
                        out.row_used[at / W] = 1;
                        std::int64_t lo[3], hi[3];
                        cell_corners(r, c, lo, hi);
                        for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
                            for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                                for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                                    const std::int64_t ca =
                                        ((z - r.o[2]) * C + (y - r.o[1])) * C + (x - r.o[0]);
                                    std::uint32_t& k = out.corner_at[static_cast<std::size_t>(ca)];
                                    if (k != k_missing) continue;
                                    k = static_cast<std::uint32_t>(out.corner_pos.size());
                                    out.corner_pos.push_back(ca);
                                }
                    }
                }
    }

    /// Density estimate at every corner (eq. 5.1-5.2). Each corner must add the deposits of its
    /// cells in reach z, y, x (then in input order), as the serial gather did: sweeping the cells in
    /// that order and pushing each cell's deposits into the corners it reaches gives every corner
    /// exactly that sequence of additions. A cell's corners (8 for g <= 1) are handled 8 at a time,
    /// one per SIMD-friendly lane, the sums held in the lanes for the cell's deposits and stored
    /// back after: the same additions in the same order.
    void estimate(const Range& r, WorkerOut& out) const {
        const std::int64_t W = m_bk.W, C = m_bk.C;
        out.sums.assign(out.corner_pos.size(), CornerSum{});
        for (std::int64_t z = r.clo[2]; z <= r.chi[2]; ++z)
            for (std::int64_t y = r.clo[1]; y <= r.chi[1]; ++y) {
                const std::int64_t row = (z - r.g0[2]) * W + (y - r.g0[1]);
                if (!out.row_used[static_cast<std::size_t>(row)]) continue;  // most rows of a surface
                for (std::int64_t x = r.clo[0]; x <= r.chi[0]; ++x) {
                    const std::uint32_t cell = out.grid[static_cast<std::size_t>(row * W + (x - r.g0[0]))];
                    if (cell == k_missing) continue;
                    const std::int64_t c[3] = {x, y, z};
                    std::int64_t lo[3], hi[3];
                    cell_corners(r, c, lo, hi);
                    out.lanes.clear();
                    for (std::int64_t qz = lo[2]; qz <= hi[2]; ++qz)
                        for (std::int64_t qy = lo[1]; qy <= hi[1]; ++qy)
                            for (std::int64_t qx = lo[0]; qx <= hi[0]; ++qx)
                                out.lanes.push_back(
                                    {out.corner_at[static_cast<std::size_t>(
                                         ((qz - r.o[2]) * C + (qy - r.o[1])) * C + (qx - r.o[0]))],
                                     {static_cast<float>(x - qx), static_cast<float>(y - qy),
                                      static_cast<float>(z - qz)}});
                    const std::uint32_t first = m_bins.cell_begin[cell], last = m_bins.cell_begin[cell + 1];
                    for (std::size_t l0 = 0; l0 < out.lanes.size(); l0 += k_lanes)
                        accumulate_lanes(&out.lanes[l0], std::min(k_lanes, out.lanes.size() - l0),
                                         &m_packed[first], last - first, m_inv_g2, out.sums.data());
                }
            }
    }

    /// Normalises the corner values, appends them to the worker's, and marks the leaves: every cell
    /// of this block with a non-zero corner.
    void mark_leaves(const Range& r, WorkerOut& out) const {
        const std::int64_t S = m_bk.S, C = m_bk.C;
        float task_max = 0.0f;
        for (std::size_t k = 0; k < out.corner_pos.size(); ++k) {
            const std::int64_t ca = out.corner_pos[k];
            const std::int64_t q[3] = {r.o[0] + ca % C, r.o[1] + (ca / C) % C, r.o[2] + ca / (C * C)};
            CornerSum& s_ = out.sums[k];
            for (float& v : s_.value) {
                v *= m_norm;
                if (std::isfinite(v)) task_max = std::max(task_max, v);
            }
            out.corner_values.insert(out.corner_values.end(), s_.value, s_.value + 3);
            if (!(s_.value[0] > 0.0f || s_.value[1] > 0.0f || s_.value[2] > 0.0f)) continue;
            for (std::uint32_t c = 0; c < 8; ++c) {
                std::int64_t v[3];
                bool inside = true;
                for (int a = 0; a < 3; ++a) {
                    v[a] = q[a] - static_cast<std::int64_t>((c >> a) & 1u);
                    inside = inside && v[a] >= r.o[a] && v[a] < r.o[a] + S && v[a] < m_bk.cells;
                }
                if (!inside) continue;
                const std::uint64_t m = pre::morton3(static_cast<std::uint32_t>(v[0] - r.o[0]),
                                                     static_cast<std::uint32_t>(v[1] - r.o[1]),
                                                     static_cast<std::uint32_t>(v[2] - r.o[2]));
                out.leaf_bits[m >> 6] |= std::uint64_t{1} << (m & 63u);
            }
        }
        out.max_value = std::max(out.max_value, task_max);
    }

    /// The marked leaves in local Morton order, with the flux-weighted normal from their corners;
    /// clears the marks.
    void emit_leaves(std::uint64_t task, WorkerOut& out) const {
        const std::int64_t C = m_bk.C;
        for (std::size_t word = 0; word < out.leaf_bits.size(); ++word) {
            for (std::uint64_t bits = out.leaf_bits[word]; bits != 0; bits &= bits - 1) {
                const std::uint64_t m = (word << 6) | static_cast<std::uint64_t>(std::countr_zero(bits));
                std::uint32_t l[3];
                pre::demorton3(m, l[0], l[1], l[2]);
                pool::GiLeaf leaf{};
                double n[3] = {0, 0, 0}, w = 0;
                for (std::uint32_t c = 0; c < 8; ++c) {
                    const std::uint32_t k =
                        out.corner_at[((l[2] + ((c >> 2) & 1u)) * C + l[1] + ((c >> 1) & 1u)) * C + l[0] +
                                      (c & 1u)];
                    leaf.corner[c] = k;
                    if (k == k_missing) continue;
                    for (int a = 0; a < 3; ++a) n[a] += out.sums[k].normal[a];
                    w += out.sums[k].weight;
                }
                const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                // One-sided when the weighted normals mostly agree: |sum w n| >= w / 2.
                for (int a = 0; a < 3; ++a)
                    leaf.normal[a] =
                        gi::encode_normal((w > 0 && len >= 0.5 * w) ? static_cast<float>(n[a] / len) : 0.0f);
                out.leaves.push_back(leaf);
                out.leaf_keys.push_back((task << m_bk.sbits) | m);
            }
            out.leaf_bits[word] = 0;
        }
    }

    const CellBins& m_bins;
    const pre::Buffer<Packed>& m_packed;
    const Blocks& m_bk;
    float m_norm, m_inv_g2;
};

/// One scale for the map (the largest corner value: every positive corner is some leaf's), then
/// the leaves in task order, their corners encoded once per task; their keys into `leaf_keys`.
void assemble_leaves(const std::vector<TaskOut>& task_out, const std::vector<WorkerOut>& worker_out,
                     unsigned threads, GiOctree& tree, pre::Buffer<std::uint64_t>& leaf_keys, float& scale) {
    float max_value = 0.0f;
    for (const WorkerOut& w : worker_out) max_value = std::max(max_value, w.max_value);
    scale = gi::map_scale(max_value);
    const std::size_t task_count = task_out.size();
    std::vector<std::size_t> leaf_offset(task_count + 1, 0);
    for (std::size_t t = 0; t < task_count; ++t) leaf_offset[t + 1] = leaf_offset[t] + task_out[t].leaf_count;
    tree.leaves.resize(leaf_offset.back());
    leaf_keys = pre::Buffer<std::uint64_t>(leaf_offset.back());
    const float zero[3] = {0.0f, 0.0f, 0.0f};
    const std::uint32_t encoded_zero = gi::encode_corner(zero, scale);
    parallel_chunks(task_count, 4, threads, [&](std::size_t begin, std::size_t end, unsigned) {
        std::vector<std::uint32_t> encoded;
        for (std::size_t t = begin; t < end; ++t) {
            const TaskOut& to = task_out[t];
            const WorkerOut& w = worker_out[to.worker];
            encoded.resize(to.corner_count);
            for (std::size_t k = 0; k < to.corner_count; ++k)
                encoded[k] = gi::encode_corner(&w.corner_values[3 * (to.corner_begin + k)], scale);
            for (std::size_t i = 0; i < to.leaf_count; ++i) {
                pool::GiLeaf leaf = w.leaves[to.leaf_begin + i];
                for (std::uint32_t& c : leaf.corner) c = c == k_missing ? encoded_zero : encoded[c];
                tree.leaves[leaf_offset[t] + i] = leaf;
                leaf_keys[leaf_offset[t] + i] = w.leaf_keys[to.leaf_begin + i];
            }
        }
    });
}

}  // namespace

// thesis 5.4.2 + eq. 5.1-5.2, in parallel over blocks of S^3 leaf cells (S = 2^s, Morton-aligned, so
// a block is a contiguous range of keys and a cell's key is its block's key << 3s | its local key).
// Each block is one independent task (BlockGather): it places the occupied cells within the gather
// reach of its corners in a dense local grid (no hash lookups), finds its corners (the lattice points
// within g of an occupied cell, as the serial gather did), estimates the density at each, and emits
// its leaves (the cells with a non-zero corner) in local Morton order. Blocks in key order then give
// the leaves sorted, with no global sort or dedupe. Corners on a block's upper faces are also
// corners of the next blocks: each block computes them again (the same sum, term for term), a few
// per cent more density work for no communication. Every corner sum adds the same terms in the same
// order as the serial gather (cells z, y, x, then deposits in input order within a cell), and the
// map scale is a maximum, so the tree is byte-identical whatever the thread count.
GiOctree build_caustic_octree(std::span<const PhotonDeposit> deposits, const double root_min[3],
                              double root_size, const GatherOptions& options) {
    const std::uint32_t depth = options.depth;
    if (depth > pool::k_max_gi_depth)
        throw Error("caustic octree depth " + std::to_string(depth) + " above " +
                    std::to_string(pool::k_max_gi_depth));
    if (!(options.radius_edges > 0.0f)) throw Error("gather radius must be positive");
    const unsigned threads = resolve_threads(options.threads);
    double mark = tool::now_seconds();
    auto phase = [&](int k) {
        const double now = tool::now_seconds();
        if (options.phase_seconds) options.phase_seconds[k] = now - mark;
        mark = now;
    };
    const CellBins bins = gi::bin_points(
        deposits.size(), root_min, root_size, depth, [&](std::size_t i) { return deposits[i].position; },
        threads, /*with_map=*/false);
    const double ge = options.radius_edges;
    const pre::Buffer<Packed> packed = pack_deposits(deposits, bins, threads);
    phase(0);

    const Blocks bk(depth, ge);
    const std::vector<std::uint64_t> tasks = block_tasks(bins, bk, depth, threads);
    phase(1);

    std::vector<TaskOut> task_out(tasks.size());
    std::vector<WorkerOut> worker_out(threads);
    const double edge_scene = bins.edge() * options.render_scale;
    const float norm = static_cast<float>(2.0 / (k_pi * (ge * edge_scene) * (ge * edge_scene)));
    const float inv_g2 = static_cast<float>(1.0 / (ge * ge));
    const BlockGather gather(bins, packed, bk, norm, inv_g2);
    parallel_chunks(tasks.size(), 1, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t t = begin; t < end; ++t) {
            task_out[t].worker = worker;
            gather.run(tasks[t], worker_out[worker], task_out[t]);
        }
    });
    phase(2);

    GiOctree tree;
    pre::Buffer<std::uint64_t> leaf_keys(0);
    float scale = 0.0f;
    assemble_leaves(task_out, worker_out, threads, tree, leaf_keys, scale);
    std::vector<WorkerOut>().swap(worker_out);
    phase(3);
    tree.nodes = gi::build_nodes(leaf_keys, depth, threads);
    gi::fill_info(tree, root_min, root_size, depth, scale);
    phase(4);
    tree.info.gather_radius = static_cast<float>(ge * bins.edge());
    tree.info.cos_threshold = options.cos_threshold;
    tree.info.sample_count = deposits.size();
    return tree;
}

}  // namespace prt::photons
