// PointRT preprocess: k-NN splat radii (thesis 3.1) through FLANN.
#include "radii.h"

#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_single_index.h>
#include <flann/util/matrix.h>
#include <flann/util/result_set.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "parallel.h"
#include "prt/error.h"
#include "prt/tool.h"

namespace prt::pre {

namespace {

std::uint64_t spread_bits(std::uint64_t v) {  // 21 bits -> every third bit of 63
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

/// Point indices sorted by the Morton code of their cell in a 2^21 grid over the bounding box.
std::vector<std::uint32_t> morton_order(std::span<const pool::Float3> p, unsigned threads) {
    float lo[3] = {p[0].x, p[0].y, p[0].z}, hi[3] = {lo[0], lo[1], lo[2]};
    for (const pool::Float3& q : p) {
        const float v[3] = {q.x, q.y, q.z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], v[a]);
            hi[a] = std::max(hi[a], v[a]);
        }
    }
    double scale[3];
    for (int a = 0; a < 3; ++a) scale[a] = hi[a] > lo[a] ? 2097151.0 / (double(hi[a]) - lo[a]) : 0.0;
    std::vector<std::uint64_t> keys(p.size());
    parallel_chunks(p.size(), 1u << 16, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) {
            const float v[3] = {p[i].x, p[i].y, p[i].z};
            std::uint64_t key = 0;
            for (int a = 0; a < 3; ++a)
                key |= spread_bits(static_cast<std::uint64_t>((double(v[a]) - lo[a]) * scale[a])) << a;
            keys[i] = key;
        }
    });
    std::vector<std::uint32_t> order(p.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
    return order;
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

    // thesis 3.1: the radius is the distance to the farthest of the k nearest neighbours. An exact
    // kd-tree (FLANN's single kd-tree, reordered copy of the data) answers each query.
    double t0 = tool::now_seconds();
    // FLANN only reads the dataset (it copies it when reordering); its Matrix wants a mutable pointer.
    flann::Matrix<float> data(const_cast<float*>(&positions[0].x), n, 3);
    flann::KDTreeSingleIndex<flann::L2_Simple<float>> index(data, flann::KDTreeSingleIndexParams(10, true));
    index.buildIndex();
    const double t1 = tool::now_seconds();

    // Queries in Morton (Z-curve) order: consecutive queries visit the same tree nodes and data,
    // which keeps them in cache (input order may be random).
    const std::vector<std::uint32_t> order = morton_order(positions, threads);
    std::vector<float> radii(n);
    if (neighbours) neighbours->assign(n * std::size_t(k), 0);
    std::atomic<std::uint64_t> done{0};
    const flann::SearchParams search(flann::FLANN_CHECKS_UNLIMITED, 0.0f, false);
    parallel_chunks(n, 4096, threads, [&](std::size_t b, std::size_t e, unsigned worker) {
        // k + 1 results: the query point itself is found at distance 0.
        flann::KNNSimpleResultSet<float> result(k + 1);
        std::vector<std::size_t> ids(k + 1);
        std::vector<float> d2(k + 1);
        for (std::size_t j = b; j < e; ++j) {
            const std::uint32_t i = order[j];
            result.clear();
            index.findNeighbors(result, &positions[i].x, search);
            radii[i] = std::sqrt(result.worstDist());
            if (neighbours) {
                // the k others: the query itself is among the k + 1 (first, unless coincident
                // points tie with it)
                result.copy(ids.data(), d2.data(), k + 1);
                std::uint32_t* out = neighbours->data() + std::size_t(i) * k;
                std::uint32_t m = 0;
                for (std::uint32_t t = 0; t <= k && m < k; ++t)
                    if (ids[t] != i) out[m++] = static_cast<std::uint32_t>(ids[t]);
            }
        }
        const std::uint64_t total = done.fetch_add(e - b) + (e - b);
        if (worker == 0 && progress) progress(total);
    });
    if (stats) {
        stats->seconds_index = t1 - t0;
        stats->seconds_search = tool::now_seconds() - t1;
    }
    return radii;
}

void clamp_radii(std::vector<float>& radii, float clamp_factor, RadiiStats& stats) {
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
    double sum = 0;
    float lo = radii[0], hi = radii[0];
    stats.zero = 0;
    for (const float r : radii) {
        sum += r;
        lo = std::min(lo, r);
        hi = std::max(hi, r);
        if (r == 0) ++stats.zero;
    }
    stats.min = lo;
    stats.max = hi;
    stats.mean = sum / double(n);
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
    clamp_radii(radii, 0.0f, stats);  // raw_median (no global clamp)
    const double raw_median = stats.raw_median;
    radii.swap(out);
    clamp_radii(radii, 0.0f, stats);  // the statistics of the result
    stats.raw_median = raw_median;
    stats.clamped = clamped.load();
}

std::vector<float> compute_radii(std::span<const pool::Float3> positions, const RadiiParams& params,
                                 RadiiStats* stats, const std::function<void(std::uint64_t)>& progress) {
    const double start = tool::now_seconds();
    RadiiStats local;
    const bool local_clamp = params.scope == ClampScope::local && params.clamp_factor > 0;
    std::vector<std::uint32_t> neighbours;
    std::vector<float> radii = knn_distances(positions, params.k, params.threads, progress, &local,
                                             local_clamp ? &neighbours : nullptr);
    if (local_clamp)
        clamp_radii_local(radii, neighbours, params.k, params.clamp_factor, local, params.threads);
    else
        clamp_radii(radii, params.clamp_factor, local);
    local.seconds = tool::now_seconds() - start;
    if (stats) *stats = local;
    return radii;
}

}  // namespace prt::pre
