#include "neighbours.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "knn.h"
#include "pca_normal.h"
#include "progress.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/symmetric_eigen.h"
#include "prt/tool_util.h"
#include "spill_file.h"

namespace prt::pre::import {

namespace {

double median_of(std::vector<float> v) {
    if (v.empty()) return 0;
    const std::size_t mid = (v.size() - 1) / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
    return v[mid];
}

}  // namespace

std::string OutlierReport::summary() const {
    if (!ran) return skipped.empty() ? std::string("not run") : skipped;
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "removed %llu of %llu points (%.3f %%): %llu statistical (mean k-NN distance above %.4g "
                  "= mean %.4g + std %.4g x ratio), %llu radius (fewer neighbours within %.4g = median "
                  "spacing %.4g x factor), in %.3f s",
                  static_cast<unsigned long long>(removed), static_cast<unsigned long long>(input),
                  input ? 100.0 * double(removed) / double(input) : 0.0,
                  static_cast<unsigned long long>(statistical), threshold, mean, stddev,
                  static_cast<unsigned long long>(radius), radius_used, median_spacing, seconds);
    return std::string(buf) + (range_scaled ? "; distances relative to the range from the scanner" : "");
}

bool outlier_removal_runs(const OutlierParams& params, std::uint64_t n, OutlierReport& report) {
    report = OutlierReport{};
    report.input = n;
    bool run = params.enabled && (params.std_ratio > 0 || params.radius_factor > 0);
    if (!params.enabled)
        report.skipped = "not run (--keep-outliers)";
    else if (!run)
        report.skipped = "not run (both tests disabled)";
    if (run && n <= params.k) {
        report.skipped = "not run: " + std::to_string(n) + " points, need more than --outlier-k " +
                         std::to_string(params.k);
        run = false;
    }
    if (run && params.min_neighbours > params.k)
        throw Error("--outlier-min-neighbours (" + std::to_string(params.min_neighbours) +
                    ") must not exceed --outlier-k (" + std::to_string(params.k) + ")");
    return run;
}

void outliers_and_graph(PointCloud& cloud, const OutlierParams& params, std::uint32_t graph_k,
                        KnnGraph* graph, OutlierReport& report, bool quiet) {
    const double t0 = tool::now_seconds();
    const std::size_t n = cloud.size();
    const bool run = outlier_removal_runs(params, n, report);
    if (!graph) graph_k = 0;
    if (!run && graph_k == 0) return;
    if (n > 0xFFFFFFFEull) throw Error("more than 2^32 - 2 points: the k-NN graph cannot index them");

    const KdTree tree(cloud.positions);
    const std::uint32_t kq = std::max(run ? params.k : 0u, graph_k);
    std::vector<float> mean_distance(run ? n : 0), mth_distance(run ? n : 0);
    if (graph_k > 0) {
        graph->k = graph_k;
        graph->neighbours.assign(n * graph_k, k_no_neighbour);
    }
    {
        LazyProgress progress("k nearest neighbours (k=" + std::to_string(kq) + ")", n, quiet);
        tree.for_each(
            kq, 0,
            [&](std::uint32_t i, const std::uint32_t* index, const float* d2, std::uint32_t found) {
                if (run) {
                    double sum = 0;
                    const std::uint32_t m = std::min(found, params.k);
                    for (std::uint32_t j = 0; j < m; ++j) sum += std::sqrt(double(d2[j]));
                    mean_distance[i] =
                        m ? static_cast<float>(sum / m) : std::numeric_limits<float>::infinity();
                    const std::uint32_t r = std::max<std::uint32_t>(params.min_neighbours, 1) - 1;
                    mth_distance[i] = r < found ? std::sqrt(d2[r]) : std::numeric_limits<float>::infinity();
                }
                if (graph_k > 0) {
                    std::uint32_t* row = graph->neighbours.data() + std::size_t{i} * graph_k;
                    for (std::uint32_t j = 0; j < std::min(found, graph_k); ++j) row[j] = index[j];
                }
            },
            [&](std::uint64_t done) { progress.update(done); });
        progress.finish();
    }
    if (!run) return;
    if (params.sensor) {
        // Relative to the range from the scanner, at the median range (the units stay lengths).
        const auto& s = *params.sensor;
        std::vector<float> range(n);
        for (std::size_t i = 0; i < n; ++i) {
            const auto& p = cloud.positions[i];
            range[i] = float(std::sqrt((p[0] - s[0]) * (p[0] - s[0]) + (p[1] - s[1]) * (p[1] - s[1]) +
                                       (p[2] - s[2]) * (p[2] - s[2])));
        }
        const double median_range = median_of(range);
        if (median_range > 0 && std::isfinite(median_range)) {
            for (std::size_t i = 0; i < n; ++i) {
                const double scale = median_range / std::max<double>(range[i], 1e-3 * median_range);
                mean_distance[i] = float(mean_distance[i] * scale);
                mth_distance[i] = float(mth_distance[i] * scale);
            }
            report.range_scaled = true;
        }
    }

    // Statistical (PCL StatisticalOutlierRemoval): mean and sample standard deviation of the
    // per-point mean distances over the whole scan; outlier above mean + ratio x std.
    double sum = 0, sum2 = 0;
    for (const float d : mean_distance) {
        sum += d;
        sum2 += double(d) * d;
    }
    report.mean = sum / double(n);
    const double variance = std::max(0.0, (sum2 - sum * sum / double(n)) / double(n - 1));
    report.stddev = std::sqrt(variance);
    report.threshold = report.mean + params.std_ratio * report.stddev;
    report.median_spacing = median_of(mean_distance);
    report.radius_used = params.radius_factor * report.median_spacing;
    report.ran = true;
    std::vector<std::uint8_t> keep(n, 1);
    for (std::size_t i = 0; i < n; ++i) {
        const bool stat = params.std_ratio > 0 && mean_distance[i] > report.threshold;
        const bool rad =
            params.radius_factor > 0 && params.min_neighbours > 0 && mth_distance[i] > report.radius_used;
        report.statistical += stat;
        report.radius += rad;
        if (stat || rad) {
            keep[i] = 0;
            ++report.removed;
        }
    }
    if (report.removed == 0) {
        report.seconds = tool::now_seconds() - t0;
        return;
    }

    if (graph_k > 0) {
        // Points that listed a removed point among their neighbours search again without them.
        std::vector<std::uint8_t> removed(n);
        for (std::size_t i = 0; i < n; ++i) removed[i] = !keep[i];
        parallel_chunks(n, 4096, resolve_threads(0), [&](std::size_t b, std::size_t e, unsigned) {
            std::vector<float> d2(graph_k);
            for (std::size_t i = b; i < e; ++i) {
                if (!keep[i]) continue;
                std::uint32_t* row = graph->neighbours.data() + i * graph_k;
                bool stale = false;
                for (std::uint32_t j = 0; j < graph_k && !stale; ++j)
                    stale = row[j] != k_no_neighbour && removed[row[j]];
                if (!stale) continue;
                const std::uint32_t found =
                    tree.nearest(static_cast<std::uint32_t>(i), graph_k, removed.data(), row, d2.data());
                for (std::uint32_t j = found; j < graph_k; ++j) row[j] = k_no_neighbour;
            }
        });
        // Renumber to the compacted point order.
        std::vector<std::uint32_t> renumber(n, k_no_neighbour);
        std::uint32_t next = 0;
        for (std::size_t i = 0; i < n; ++i)
            if (keep[i]) renumber[i] = next++;
        std::size_t out = 0;
        for (std::size_t i = 0; i < n; ++i) {
            if (!keep[i]) continue;
            for (std::uint32_t j = 0; j < graph_k; ++j) {
                const std::uint32_t m = graph->neighbours[i * graph_k + j];
                graph->neighbours[out * graph_k + j] = m == k_no_neighbour ? k_no_neighbour : renumber[m];
            }
            ++out;
        }
        graph->neighbours.resize(out * graph_k);
    }
    keep_points(cloud, keep);
    report.seconds = tool::now_seconds() - t0;
}

std::vector<pool::Float3> pca_normals(const std::vector<std::array<double, 3>>& positions,
                                      const KnnGraph& graph, std::uint32_t k, bool quiet) {
    const std::size_t n = positions.size();
    const std::uint32_t gk = graph.k;
    if (k < 3) throw Error("--k must be at least 3 for PCA normals");
    const std::uint32_t others = std::min(k - 1, gk);
    std::vector<pool::Float3> normals(n, {std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f});
    LazyProgress progress("estimating normals (PCA, k=" + std::to_string(k) + ")", n, quiet);
    parallel_chunks(n, 4096, resolve_threads(0), [&](std::size_t b, std::size_t e, unsigned worker) {
        for (std::size_t i = b; i < e; ++i)
            pca_normal(
                positions[i], graph.neighbours.data() + i * gk, others,
                [&](std::uint32_t j) -> const std::array<double, 3>& { return positions[j]; }, normals[i]);
        if (worker == 0) progress.update(e);
    });
    progress.finish();
    return normals;
}

void pca_normals_tiled(std::span<const std::array<double, 3>> positions, std::uint32_t k,
                       TiledKnnParams tiling, std::span<pool::Float3> normals, TiledKnnStats* stats,
                       const std::function<void(std::uint64_t)>& progress,
                       const std::array<double, 3>* centre_in) {
    const std::size_t n = positions.size();
    if (k < 3) throw Error("--k must be at least 3 for PCA normals");
    if (normals.size() != n) throw Error("internal: pca_normals_tiled: normals of the wrong size");
    // The in-core KdTree's coordinates (knn.cpp): float offsets from the bounding-box centre.
    const bool input_mapped = tiling.positions_mapped;
    std::array<double, 3> lo = n ? positions[0] : std::array<double, 3>{0, 0, 0}, hi = lo;
    if (!centre_in)
        for (const auto& p : positions)
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], p[a]);
                hi[a] = std::max(hi[a], p[a]);
            }
    const std::array<double, 3> centre =
        centre_in
            ? *centre_in
            : std::array<double, 3>{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    SpillFile offsets(tiling.spill_folder, std::uint64_t(n) * sizeof(pool::Float3), "the float positions");
    const std::span<pool::Float3> f = offsets.as<pool::Float3>();
    for (std::size_t i = 0; i < n; ++i) {
        f[i] = {static_cast<float>(positions[i][0] - centre[0]),
                static_cast<float>(positions[i][1] - centre[1]),
                static_cast<float>(positions[i][2] - centre[2])};
        if ((i + 1) % (std::size_t{1} << 20) == 0) {
            offsets.drop();  // written pages stay in the file
            if (input_mapped) drop_pages(positions.data(), (i + 1) * sizeof positions[0]);
        }
    }
    offsets.drop();
    if (input_mapped) drop_pages(positions.data(), n * sizeof positions[0]);
    // PCA takes the k - 1 nearest others: the first k - 1 of the in-core graph's k (same ties).
    tiling.k = k - 1;
    tiling.positions_mapped = true;  // the spill file above
    std::fill(normals.begin(), normals.end(),
              pool::Float3{std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f});
    const unsigned threads = resolve_threads(tiling.threads);
    tiled_knn(
        f, tiling,
        [&](const KnnBatch& batch) {
            parallel_chunks(batch.queries.size(), 1024, threads, [&](std::size_t b, std::size_t e, unsigned) {
                std::vector<std::uint32_t> row(k - 1);
                for (std::size_t q = b; q < e; ++q) {
                    for (std::uint32_t j = 0; j < k - 1; ++j)
                        row[j] = batch.global[batch.neighbours[q * (k - 1) + j]];
                    const std::uint32_t g = batch.global[batch.queries[q]];
                    pca_normal(
                        positions[g], row.data(), k - 1,
                        [&](std::uint32_t j) -> const std::array<double, 3>& { return positions[j]; },
                        normals[g]);
                }
            });
        },
        progress, stats);
}

}  // namespace prt::pre::import
