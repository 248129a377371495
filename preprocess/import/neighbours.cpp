#include "neighbours.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "knn.h"
#include "progress.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/symmetric_eigen.h"
#include "prt/tool.h"

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

void outliers_and_graph(PointCloud& cloud, const OutlierParams& params, std::uint32_t graph_k,
                        KnnGraph* graph, OutlierReport& report, bool quiet) {
    const double t0 = tool::now_seconds();
    const std::size_t n = cloud.size();
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
        for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t* row = graph.neighbours.data() + i * gk;
            // Coordinates relative to the point itself: double sums of small numbers.
            double d[257][3];
            std::uint32_t m = 0;
            d[m][0] = d[m][1] = d[m][2] = 0.0;
            ++m;
            for (std::uint32_t j = 0; j < others; ++j) {
                if (row[j] == k_no_neighbour) break;
                for (int a = 0; a < 3; ++a) d[m][a] = positions[row[j]][a] - positions[i][a];
                ++m;
            }
            if (m < 3) continue;
            double mean[3] = {0, 0, 0};
            for (std::uint32_t j = 0; j < m; ++j)
                for (int a = 0; a < 3; ++a) mean[a] += d[j][a];
            for (int a = 0; a < 3; ++a) mean[a] /= m;
            std::array<Vec3d, 3> c{};
            for (std::uint32_t j = 0; j < m; ++j) {
                const double x = d[j][0] - mean[0], y = d[j][1] - mean[1], z = d[j][2] - mean[2];
                c[0][0] += x * x;
                c[0][1] += x * y;
                c[0][2] += x * z;
                c[1][1] += y * y;
                c[1][2] += y * z;
                c[2][2] += z * z;
            }
            c[1][0] = c[0][1];
            c[2][0] = c[0][2];
            c[2][1] = c[1][2];
            const SymmetricEigen eigen = symmetric_eigen(c);
            const Vec3d& w = eigen.values;
            const Vec3d& v = eigen.vectors[0];
            if (!(w[2] > 0.0) || w[1] <= 1e-10 * w[2]) continue;  // coincident or collinear
            const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (!(len > 0.0) || !std::isfinite(len)) continue;
            normals[i] = {static_cast<float>(v[0] / len), static_cast<float>(v[1] / len),
                          static_cast<float>(v[2] / len)};
        }
        if (worker == 0) progress.update(e);
    });
    progress.finish();
    return normals;
}

}  // namespace prt::pre::import
