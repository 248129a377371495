// PointRT preprocess: k-NN splat radii (thesis 3.1) through the shared exact kd-tree (kd_tree.h).
#include "radii.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "backend_choice.h"
#include "buffer.h"
#include "kd_tree.h"
#ifdef PRT_HAVE_CUDA
#include "prt/cuda/knn_cuda.h"
#endif
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"

namespace prt::pre {

namespace {

/// Minimum, maximum, sum and zeros of the final radii. The sum is taken in blocks of
/// k_summary_block values in index order, each block summed from zero and the block sums added in
/// order, so that every path gets the same bits: summarize() over threads (the in-core and GPU
/// paths: the host's one-thread pass over the 500M room's radii took most of a second) and the
/// streamed statistics block by block.
constexpr std::size_t k_summary_block = std::size_t{1} << 20;

struct RadiusSummary {
    double sum = 0;
    float lo = 0, hi = 0;
    std::uint64_t zero = 0, count = 0;
    /// One block of at most k_summary_block values, after the blocks before it.
    void add_block(std::span<const float> values) {
        RadiusSummary b;  // summed from zero
        for (const float r : values) {
            b.sum += r;
            b.lo = b.count == 0 ? r : std::min(b.lo, r);
            b.hi = b.count == 0 ? r : std::max(b.hi, r);
            if (r == 0) ++b.zero;
            ++b.count;
        }
        merge(b);
    }
    /// The summary of the values after this one's.
    void merge(const RadiusSummary& b) {
        if (b.count == 0) return;
        sum += b.sum;
        lo = count == 0 ? b.lo : std::min(lo, b.lo);
        hi = count == 0 ? b.hi : std::max(hi, b.hi);
        zero += b.zero;
        count += b.count;
    }
    void into(RadiiStats& stats) const {
        stats.min = lo;
        stats.max = hi;
        stats.mean = sum / double(count);
        stats.zero = zero;
    }
};

/// The summary of `values`, its blocks on `threads` workers.
RadiusSummary summarize(std::span<const float> values, unsigned threads) {
    const std::size_t blocks = (values.size() + k_summary_block - 1) / k_summary_block;
    std::vector<RadiusSummary> part(blocks);
    parallel_chunks(blocks, 1, resolve_threads(threads), [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) {
            const std::size_t first = i * k_summary_block;
            part[i].add_block(values.subspan(first, std::min(k_summary_block, values.size() - first)));
        }
    });
    RadiusSummary all;
    for (const RadiusSummary& p : part) all.merge(p);
    return all;
}

/// The checks every compute_radii path makes before searching (knn_distances' own, and the clamp's).
void check_radii_params(std::size_t n, const RadiiParams& params) {
    const std::uint32_t k = params.k;
    if (k == 0) throw Error("k-NN radii: k must be at least 1");
    if (n <= k)
        throw Error("k-NN radii: " + std::to_string(n) + " points, need more than k = " + std::to_string(k) +
                    " (lower --k)");
    if (!(params.clamp_factor >= 0) || !std::isfinite(params.clamp_factor))
        throw Error("k-NN radii: the clamp factor must be finite and >= 0");
}

}  // namespace

const char* clamp_scope_name(ClampScope s) {
    return s == ClampScope::local ? "local" : "global";
}

ClampScope parse_clamp_scope(const std::string& name) {
    if (name == "local") return ClampScope::local;
    if (name == "global") return ClampScope::global;
    throw Error("unknown clamp scope '" + name + "' (local or global)");
}

std::vector<float> knn_distances(std::span<const pool::Float3> positions, std::uint32_t k, unsigned threads,
                                 const std::function<void(std::uint64_t)>& progress, RadiiStats* stats,
                                 std::vector<std::uint32_t>* neighbours) {
    static_assert(sizeof(pool::Float3) == 3 * sizeof(float));
    const std::size_t n = positions.size();
    if (k == 0) throw Error("k-NN radii: k must be at least 1");
    if (n <= k)
        throw Error("k-NN radii: " + std::to_string(n) + " points, need more than k = " + std::to_string(k) +
                    " (lower --k)");
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(positions[i].x) || !std::isfinite(positions[i].y) ||
            !std::isfinite(positions[i].z))
            throw Error("k-NN radii: point " + std::to_string(i) + " has a non-finite position");
    threads = resolve_threads(threads);

    // thesis 3.1: the radius is the distance to the farthest of the k nearest neighbours, found by
    // an exact kd-tree over the float positions (squared distances in float).
    const double t0 = tool::now_seconds();
    const KdTree<float> tree(
        n,
        [&](std::size_t i, float c[3]) {
            c[0] = positions[i].x;
            c[1] = positions[i].y;
            c[2] = positions[i].z;
        },
        threads);
    const double t1 = tool::now_seconds();

    std::vector<float> radii(n);
    if (neighbours) neighbours->assign(n * std::size_t(k), 0);
    tree.for_each(
        k, threads,
        [&](std::uint32_t i, const std::uint32_t* index, const float* distance2, std::uint32_t) {
            radii[i] = std::sqrt(distance2[k - 1]);  // n > k: k others are always found
            if (neighbours)
                std::memcpy(neighbours->data() + std::size_t(i) * k, index, k * sizeof(std::uint32_t));
        },
        progress);
    if (stats) {
        stats->seconds_index = t1 - t0;
        stats->seconds_search = tool::now_seconds() - t1;
    }
    return radii;
}

void clamp_radii(std::vector<float>& radii, float clamp_factor, RadiiStats& stats, unsigned threads) {
    if (!(clamp_factor >= 0) || !std::isfinite(clamp_factor))
        throw Error("k-NN radii: the clamp factor must be finite and >= 0");
    const std::size_t n = radii.size();
    stats.points = n;
    if (n == 0) return;
    auto median_of = [](std::vector<float> v) {
        const std::size_t mid = (v.size() - 1) / 2;
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
        double m = v[mid];
        if (v.size() % 2 == 0)
            m = 0.5 * (m + *std::min_element(v.begin() + static_cast<std::ptrdiff_t>(mid) + 1, v.end()));
        return m;
    };
    stats.raw_median = median_of(radii);
    stats.clamped = 0;
    stats.clamp_limit = 0;
    if (clamp_factor > 0) {
        const float limit = static_cast<float>(double(clamp_factor) * stats.raw_median);
        stats.clamp_limit = limit;
        for (float& r : radii)
            if (r > limit) {
                r = limit;
                ++stats.clamped;
            }
    }
    summarize(radii, threads).into(stats);
    stats.median = median_of(radii);
}

void clamp_radii_local(std::vector<float>& radii, const std::vector<std::uint32_t>& neighbours,
                       std::uint32_t k, float clamp_factor, RadiiStats& stats, unsigned threads) {
    if (!(clamp_factor > 0) || !std::isfinite(clamp_factor))
        throw Error("k-NN radii: the local clamp factor must be finite and > 0");
    const std::size_t n = radii.size();
    if (neighbours.size() != n * std::size_t(k)) throw Error("k-NN radii: neighbour list of the wrong size");
    std::vector<float> out(radii);
    std::atomic<std::uint64_t> clamped{0};
    parallel_chunks(n, 4096, resolve_threads(threads), [&](std::size_t b, std::size_t e, unsigned) {
        std::vector<float> v(k);
        std::uint64_t c = 0;
        for (std::size_t i = b; i < e; ++i) {
            for (std::uint32_t j = 0; j < k; ++j) v[j] = radii[neighbours[i * k + j]];
            std::nth_element(v.begin(), v.begin() + k / 2, v.end());
            const float limit = clamp_factor * v[k / 2];
            if (radii[i] > limit) out[i] = limit, ++c;
        }
        clamped += c;
    });
    clamp_radii(radii, 0.0f, stats, threads);  // raw_median (no global clamp)
    const double raw_median = stats.raw_median;
    radii.swap(out);
    clamp_radii(radii, 0.0f, stats, threads);  // the statistics of the result
    stats.raw_median = raw_median;
    stats.clamped = clamped.load();
}

bool radii_gpu_pays(std::uint64_t n, unsigned threads) {
    return n >= std::uint64_t{100000} * resolve_threads(threads);
}

std::string resolve_radii_backend(const std::string& name, std::uint64_t n, std::uint32_t k, unsigned threads,
                                  std::string* why) {
    if (name == "auto" && !radii_gpu_pays(n, threads)) {
        if (why) *why = "under 100k points per CPU thread the CPU is as fast";
        return "cpu";
    }
#ifdef PRT_HAVE_CUDA
    return choose_backend(
        name, [&](std::string* reason) { return cuda::knn_radii_usable(n, k, reason); }, why);
#else
    (void)k;
    return choose_backend(name, no_cuda_build, why);
#endif
}

RadiiPlan plan_radii(std::uint64_t n, const RadiiParams& params, std::uint64_t memory, bool force_tiles,
                     std::string* why) {
    RadiiPlan plan;
    if (params.backend == "auto" && (force_tiles || 4 * n > memory)) {
        plan.backend = "cpu";
        if (why)
            *why = force_tiles ? "--tile-points tests the CPU's out-of-core search"
                               : "the radii alone, 4 bytes per point, exceed --memory";
    } else {
        plan.backend = resolve_radii_backend(params.backend, n, params.k, params.threads, why);
    }
    plan.tiled = plan.backend == "cpu" && (force_tiles || radii_in_core_bytes(n, params) > memory);
    return plan;
}

namespace {

#ifdef PRT_HAVE_CUDA
/// compute_radii() on device 0: the search, the clamp and the medians there, the sums here (in
/// index order, as clamp_radii adds them).
std::vector<float> compute_radii_cuda(std::span<const pool::Float3> positions, const RadiiParams& params,
                                      RadiiStats& stats, const std::function<void(std::uint64_t)>& progress) {
    const std::size_t n = positions.size();
    const std::uint32_t k = params.k;
    check_radii_params(n, params);
    const cuda::KnnClamp clamp = params.clamp_factor == 0            ? cuda::KnnClamp::none
                                 : params.scope == ClampScope::local ? cuda::KnnClamp::local
                                                                     : cuda::KnnClamp::global;
    // The 4 bytes a point the search downloads into: huge pages, first touched by every worker
    // (the 500M room's 2 GB were faulted in 4 KiB at a time by the zeroing on this thread).
    std::vector<float> radii;
    resize_on_huge_pages(radii, n, resolve_threads(params.threads));
    const cuda::KnnRadiiResult r =
        cuda::knn_radii_cuda({reinterpret_cast<const float*>(positions.data()), 3 * n}, k, clamp,
                             params.clamp_factor, radii, progress);
    if (r.non_finite >= 0)
        throw Error("k-NN radii: point " + std::to_string(r.non_finite) + " has a non-finite position");
    stats.points = n;
    stats.raw_median = r.raw_median;
    stats.clamp_limit = r.clamp_limit;
    stats.clamped = r.clamped;
    summarize(radii, params.threads).into(stats);
    stats.median = r.median;
    stats.seconds_index = r.seconds_upload + r.seconds_index;
    stats.seconds_search = r.seconds_search;
    stats.backend = "cuda";
    return radii;
}
#endif

}  // namespace

std::vector<float> compute_radii(std::span<const pool::Float3> positions, const RadiiParams& params,
                                 RadiiStats* stats, const std::function<void(std::uint64_t)>& progress) {
    const double start = tool::now_seconds();
    if (params.backend != "cpu") {
#ifdef PRT_HAVE_CUDA
        if (params.backend != "cuda")
            throw Error("k-NN radii: unknown backend '" + params.backend + "' (resolve it first)");
        RadiiStats local;
        std::vector<float> radii = compute_radii_cuda(positions, params, local, progress);
        local.seconds = tool::now_seconds() - start;
        if (stats) *stats = local;
        return radii;
#else
        throw Error("k-NN radii: backend '" + params.backend + "': this build has no CUDA backend");
#endif
    }
    RadiiStats local;
    const bool local_clamp = params.scope == ClampScope::local && params.clamp_factor > 0;
    std::vector<std::uint32_t> neighbours;
    std::vector<float> radii = knn_distances(positions, params.k, params.threads, progress, &local,
                                             local_clamp ? &neighbours : nullptr);
    if (local_clamp)
        clamp_radii_local(radii, neighbours, params.k, params.clamp_factor, local, params.threads);
    else
        clamp_radii(radii, params.clamp_factor, local, params.threads);
    local.seconds = tool::now_seconds() - start;
    if (stats) *stats = local;
    return radii;
}

std::uint64_t radii_in_core_bytes(std::uint64_t n, const RadiiParams& params) {
    // kd-tree (16-byte points, slot map, splits) + radii + the clamped copy, and the k neighbour
    // indices per point for the local clamp.
    const bool local = params.scope == ClampScope::local && params.clamp_factor > 0;
    return n * (24 + 4 + 4 + (local ? 4 * std::uint64_t(params.k) : 0));
}

namespace {

std::uint32_t order_key(float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

float from_order_key(std::uint32_t key) {
    const std::uint32_t u = (key & 0x80000000u) ? (key & 0x7fffffffu) : ~key;
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
}

/// Calls f(block) for every k_summary_block values in order (the last block shorter), dropping the
/// pages of each 4M-value step once read (the spans here are spill files: prt::drop_mapped_pages).
template <class F>
void stream_blocks(std::span<const float> values, bool mapped, F&& f) {
    constexpr std::size_t step = std::size_t{1} << 22;
    static_assert(step % k_summary_block == 0, "a step holds whole blocks");
    for (std::size_t s = 0; s < values.size(); s += step) {
        const std::size_t e = std::min(values.size(), s + step);
        for (std::size_t b = s; b < e; b += k_summary_block)
            f(values.subspan(b, std::min(k_summary_block, e - b)));
        if (mapped) drop_pages(values.data() + s, (e - s) * sizeof(float));
    }
}

/// Calls f(v) for every value in order, as stream_blocks reads them.
template <class F>
void stream(std::span<const float> values, bool mapped, F&& f) {
    stream_blocks(values, mapped, [&](std::span<const float> block) {
        for (const float v : block) f(v);
    });
}

/// The element of rank `rank` (0-based) in sorted order: two radix passes of 16 bits.
float select_rank(std::span<const float> values, std::uint64_t rank, bool mapped) {
    std::vector<std::uint64_t> hist(65536, 0);
    stream(values, mapped, [&](float v) { ++hist[order_key(v) >> 16]; });
    std::uint32_t high = 0;
    while (rank >= hist[high]) rank -= hist[high++];
    std::fill(hist.begin(), hist.end(), 0);
    stream(values, mapped, [&](float v) {
        const std::uint32_t key = order_key(v);
        if ((key >> 16) == high) ++hist[key & 0xffffu];
    });
    std::uint32_t low = 0;
    while (rank >= hist[low]) rank -= hist[low++];
    return from_order_key((high << 16) | low);
}

/// clamp_radii(radii, 0, stats) over a span: everything but the clamp.
void streamed_statistics(std::span<const float> radii, RadiiStats& stats) {
    const std::size_t n = radii.size();
    stats.points = n;
    stats.clamped = 0;
    stats.clamp_limit = 0;
    if (n == 0) return;
    stats.raw_median = median_streaming(radii, true);
    RadiusSummary summary;  // block by block, as summarize() adds them
    stream_blocks(radii, true, [&](std::span<const float> block) { summary.add_block(block); });
    summary.into(stats);
    stats.median = stats.raw_median;
}

}  // namespace

double median_streaming(std::span<const float> values, bool mapped) {
    if (values.empty()) return 0;
    const std::size_t mid = (values.size() - 1) / 2;
    double m = select_rank(values, mid, mapped);
    if (values.size() % 2 == 0) m = 0.5 * (m + select_rank(values, mid + 1, mapped));
    return m;
}

SpillFile compute_radii_tiled(std::span<const pool::Float3> positions, const RadiiParams& params,
                              TiledKnnParams tiling, RadiiStats* stats, TiledKnnStats* tiling_stats,
                              const std::function<void(std::uint64_t)>& progress) {
    const double start = tool::now_seconds();
    const std::size_t n = positions.size();
    const std::uint32_t k = params.k;
    check_radii_params(n, params);
    tiling.k = k;
    tiling.threads = params.threads;
    const unsigned threads = resolve_threads(params.threads);
    const bool local_clamp = params.scope == ClampScope::local && params.clamp_factor > 0;

    // The raw radii (index order) and, for the local clamp, each point's k neighbours (global).
    SpillFile raw(tiling.spill_folder, std::uint64_t(n) * sizeof(float), "the raw radii");
    SpillFile neighbours;
    if (local_clamp)
        neighbours = SpillFile(tiling.spill_folder, std::uint64_t(n) * k * sizeof(std::uint32_t),
                               "the neighbour lists");
    float* r = raw.as<float>().data();
    std::uint32_t* nb = local_clamp ? neighbours.as<std::uint32_t>().data() : nullptr;
    TiledKnnStats tstats;
    tiled_knn(
        positions, tiling,
        [&](const KnnBatch& batch) {
            parallel_chunks(batch.queries.size(), 4096, threads, [&](std::size_t b, std::size_t e, unsigned) {
                for (std::size_t q = b; q < e; ++q) {
                    const std::uint32_t g = batch.global[batch.queries[q]];
                    r[g] = std::sqrt(batch.distance2[q * k + k - 1]);  // as knn_distances
                    if (nb)
                        for (std::uint32_t j = 0; j < k; ++j)
                            nb[std::size_t(g) * k + j] = batch.global[batch.neighbours[q * k + j]];
                }
            });
            raw.drop();
            if (nb) neighbours.drop();
        },
        progress, &tstats);

    RadiiStats local;
    local.seconds_index = tstats.seconds_bucket;
    local.seconds_search = tstats.seconds_search;
    SpillFile out;
    if (local_clamp) {
        // clamp_radii_local, streamed in index order.
        out = SpillFile(tiling.spill_folder, std::uint64_t(n) * sizeof(float), "the radii");
        float* o = out.as<float>().data();
        std::atomic<std::uint64_t> clamped{0};
        const std::size_t block = std::size_t{1} << 18;  // 9.4 MB of neighbour lists at k = 9
        for (std::size_t base = 0; base < n; base += block) {
            const std::size_t end = std::min(n, base + block);
            parallel_chunks(end - base, 4096, threads, [&](std::size_t b, std::size_t e, unsigned) {
                std::vector<float> v(k);
                std::uint64_t c = 0;
                for (std::size_t i = base + b; i < base + e; ++i) {
                    for (std::uint32_t j = 0; j < k; ++j) v[j] = r[nb[i * k + j]];
                    std::nth_element(v.begin(), v.begin() + k / 2, v.end());
                    const float limit = params.clamp_factor * v[k / 2];
                    o[i] = r[i] > limit ? (++c, limit) : r[i];
                }
                clamped += c;
            });
            drop_pages(nb + base * k, (end - base) * k * sizeof(std::uint32_t));
            out.drop();
        }
        neighbours = SpillFile();
        streamed_statistics(raw.as<const float>(), local);
        const double raw_median = local.raw_median;
        raw = SpillFile();
        streamed_statistics(out.as<const float>(), local);
        local.raw_median = raw_median;
        local.clamped = clamped.load();
    } else {
        // clamp_radii with the global median, in place.
        const std::span<float> radii = raw.as<float>();
        const double raw_median = median_streaming(radii, true);
        std::uint64_t clamped = 0;
        double limit = 0;
        if (params.clamp_factor > 0) {
            const float l = static_cast<float>(double(params.clamp_factor) * raw_median);
            limit = l;
            for (std::size_t i = 0; i < radii.size(); ++i) {
                if (radii[i] > l) radii[i] = l, ++clamped;
                if ((i + 1) % (std::size_t{1} << 22) == 0) raw.drop();
            }
        }
        streamed_statistics(radii, local);
        local.raw_median = raw_median;
        local.clamped = clamped;
        local.clamp_limit = limit;
        out = std::move(raw);
    }
    out.drop();
    if (tiling.positions_mapped) drop_pages(positions.data(), positions.size_bytes());
    local.seconds = tool::now_seconds() - start;
    if (stats) *stats = local;
    if (tiling_stats) *tiling_stats = tstats;
    return out;
}

}  // namespace prt::pre
