// PointRT prt-import out of core (issue 17): see out_of_core.h.
#include "out_of_core.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <type_traits>

#include "neighbours.h"
#include "orient_propagate.h"
#include "pcd_header.h"
#include "ply_reader.h"
#include "poses.h"
#include "prt/error.h"
#include "prt/formats/pool.h"
#include "prt/mapped_file.h"
#include "prt/tool_util.h"
#include "tiled_knn.h"
#include "xyz_reader.h"

namespace prt::pre::import {

namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t k_drop_every = std::uint64_t{1} << 20;  // points between page drops

std::string fmt(const char* format, double a) {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, a);
    return buf;
}

std::string sensor_text(const pool::Sensor& s) {
    return (s.kind == pool::k_sensor_direction ? "direction " : "point ") + std::string("(") +
           fmt("%g", s.position[0]) + ", " + fmt("%g", s.position[1]) + ", " + fmt("%g", s.position[2]) + ")";
}

template <class T>
SpillArray<T> make_spill(const MemoryParams& memory, std::uint64_t count, const char* what) {
    return {std::make_shared<SpillFile>(memory.spill_folder, std::max<std::uint64_t>(count, 1) * sizeof(T),
                                        what)};
}

/// The spilled per-point arrays while they are being filled (`n` points so far).
struct Arrays {
    SpilledCloud cloud;
    bool normals = false, colors = false, radii = false, intensities = false, scan_ids = false;
    SpillArray<std::uint8_t> given;  ///< merged, some scans with normals: per point, the file's normal

    void drop() const {
        for (const SpillFile* f : {cloud.positions.file.get(), cloud.normals.file.get(),
                                   cloud.colors.file.get(), cloud.radii.file.get(),
                                   cloud.intensities.file.get(), cloud.scan_ids.file.get(), given.file.get()})
            if (f) f->drop();
    }
    /// Keeps the points whose keep[i] is set, in order (keep_points()); returns how many.
    std::uint64_t compact(std::span<const std::uint8_t> keep) {
        const auto p = cloud.positions.span();
        const auto nn = cloud.normals.span();
        const auto c = cloud.colors.span();
        const auto r = cloud.radii.span();
        const auto in = cloud.intensities.span();
        const auto ids = cloud.scan_ids.span();
        const auto gv = given.span();
        std::uint64_t out = 0;
        for (std::uint64_t i = 0; i < cloud.size; ++i) {
            if (keep[i]) {
                p[out] = p[i];
                if (normals) nn[out] = nn[i];
                if (colors) c[out] = c[i];
                if (radii) r[out] = r[i];
                if (intensities) in[out] = in[i];
                if (scan_ids) ids[out] = ids[i];
                if (given.file) gv[out] = gv[i];
                ++out;
            }
            if ((i + 1) % k_drop_every == 0) drop();
        }
        drop();
        cloud.size = out;
        return out;
    }
};

/// The bounding-box centre of positions (knn.cpp's box_centre), read once.
std::array<double, 3> box_centre(std::span<const std::array<double, 3>> positions) {
    if (positions.empty()) return {0, 0, 0};
    std::array<double, 3> lo = positions[0], hi = positions[0];
    for (std::size_t i = 0; i < positions.size(); ++i) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], positions[i][a]);
            hi[a] = std::max(hi[a], positions[i][a]);
        }
        if ((i + 1) % k_drop_every == 0) drop_pages(positions.data(), (i + 1) * sizeof positions[0]);
    }
    drop_pages(positions.data(), positions.size() * sizeof positions[0]);  // a spill file
    return {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
}

/// clean()'s exact duplicate removal out of core: the (hash, index) keys go to buckets by hash
/// (a spill file sorted by bucket, each bucket within the memory); each bucket is sorted as clean()
/// sorts all keys and its runs of equal hashes compared the same way. Equal positions have equal
/// hashes, so they meet in one bucket: the same first occurrences are kept. Clears keep[i] of the
/// duplicates and returns their count.
std::uint64_t drop_duplicates(std::span<const std::array<double, 3>> positions,
                              const SpillFile& positions_file, std::span<std::uint8_t> keep,
                              const MemoryParams& memory, bool quiet) {
    struct Key {
        std::uint64_t hash;
        std::uint64_t index;
    };
    const std::uint64_t n = positions.size();
    // A bucket's keys in memory plus the same in the mapped spill file while they are copied.
    const std::uint64_t per_bucket = std::max<std::uint64_t>(memory.memory / 4 / sizeof(Key), 1024);
    const std::uint64_t buckets = std::min<std::uint64_t>(
        std::uint64_t{1} << 24,
        memory.tile_points ? std::max<std::uint64_t>(4, n / std::max<std::uint64_t>(memory.tile_points, 1))
                           : (n + per_bucket - 1) / per_bucket);
    auto bucket_of = [&](std::uint64_t h) { return ((h >> 32) * buckets) >> 32; };
    std::vector<std::uint64_t> begin(buckets + 1, 0);
    for (std::uint64_t i = 0; i < n; ++i) {
        if (keep[i]) ++begin[bucket_of(position_hash(positions[i])) + 1];
        if ((i + 1) % k_drop_every == 0) positions_file.drop();
    }
    positions_file.drop();
    for (std::uint64_t b = 0; b < buckets; ++b) begin[b + 1] += begin[b];
    SpillFile records(memory.spill_folder, std::max<std::uint64_t>(begin[buckets], 1) * sizeof(Key),
                      "the duplicate keys");
    const std::span<Key> r = records.as<Key>();
    {
        std::vector<std::uint64_t> fill(begin.begin(), begin.end() - 1);
        for (std::uint64_t i = 0; i < n; ++i) {
            if (!keep[i]) continue;
            const std::uint64_t h = position_hash(positions[i]);
            r[fill[bucket_of(h)]++] = {h, i};
            if ((i + 1) % k_drop_every == 0) {
                records.drop();
                positions_file.drop();
            }
        }
        records.drop();
        positions_file.drop();
    }
    std::uint64_t duplicates = 0;
    tool::Progress progress("prt-import: exact duplicates by hash buckets", buckets, quiet);
    std::vector<Key> keys;
    for (std::uint64_t b = 0; b < buckets; ++b) {
        keys.assign(r.begin() + static_cast<std::ptrdiff_t>(begin[b]),
                    r.begin() + static_cast<std::ptrdiff_t>(begin[b + 1]));
        records.drop();
        std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& c) {
            return a.hash != c.hash ? a.hash < c.hash : a.index < c.index;
        });
        for (std::size_t run = 0; run < keys.size();) {
            std::size_t end = run + 1;
            while (end < keys.size() && keys[end].hash == keys[run].hash) ++end;
            for (std::size_t a = run; a < end; ++a) {
                if (!keep[keys[a].index]) continue;
                for (std::size_t c = a + 1; c < end; ++c)
                    if (keep[keys[c].index] && positions[keys[c].index] == positions[keys[a].index]) {
                        keep[keys[c].index] = 0;
                        ++duplicates;
                    }
            }
            run = end;
        }
        records.drop();
        positions_file.drop();
        progress.update(b + 1);
    }
    progress.finish();
    keys = {};
    return duplicates;
}

/// The float offsets from `centre` the in-core KdTree searches (knn.cpp), in a spill file.
SpillFile float_offsets(std::span<const std::array<double, 3>> positions, const std::array<double, 3>& centre,
                        const MemoryParams& memory) {
    // `positions` is a spill file: its pages leave the resident set as they are read.
    SpillFile f(memory.spill_folder, std::max<std::size_t>(positions.size(), 1) * sizeof(pool::Float3),
                "the float positions");
    const auto out = f.as<pool::Float3>();
    for (std::size_t i = 0; i < positions.size(); ++i) {
        out[i] = {static_cast<float>(positions[i][0] - centre[0]),
                  static_cast<float>(positions[i][1] - centre[1]),
                  static_cast<float>(positions[i][2] - centre[2])};
        if ((i + 1) % k_drop_every == 0) {
            f.drop();
            drop_pages(positions.data(), (i + 1) * sizeof positions[0]);
        }
    }
    f.drop();
    drop_pages(positions.data(), positions.size() * sizeof positions[0]);
    return f;
}

TiledKnnParams tiling_of(const MemoryParams& memory, std::uint32_t k) {
    TiledKnnParams t;
    t.k = k;
    t.memory = memory.memory;
    t.tile_points = memory.tile_points;
    t.spill_folder = memory.spill_folder;
    t.positions_mapped = true;
    return t;
}

/// outliers_and_graph()'s outlier removal (neighbours.cpp) over tiled_knn(): the same per-point
/// mean and m-th distances (the first k of the same exact neighbours, ties by index), the same
/// sums in index order and the same medians. Clears keep[i] of the outliers.
void remove_outliers_tiled(std::span<const std::array<double, 3>> positions,
                           const std::array<double, 3>& centre, const OutlierParams& params,
                           std::span<std::uint8_t> keep, OutlierReport& report, const MemoryParams& memory,
                           bool quiet) {
    const double t0 = tool::now_seconds();
    const std::uint64_t n = positions.size();
    if (!outlier_removal_runs(params, n, report)) return;
    if (n > 0xFFFFFFFEull) throw Error("more than 2^32 - 2 points: the k-NN graph cannot index them");

    SpillFile distances(memory.spill_folder, n * 2 * sizeof(float), "the outlier distances");
    const std::span<float> mean_distance = distances.as<float>().subspan(0, n);
    const std::span<float> mth_distance = distances.as<float>().subspan(n, n);
    {
        const SpillFile offsets = float_offsets(positions, centre, memory);
        const std::uint32_t k = params.k;
        const std::uint32_t r = std::max<std::uint32_t>(params.min_neighbours, 1) - 1;
        tool::Progress progress("prt-import: outliers, k-NN by tiles (k=" + std::to_string(k) + ")", n,
                                quiet);
        tiled_knn(
            offsets.as<const pool::Float3>(), tiling_of(memory, k),
            [&](const KnnBatch& batch) {
                for (std::size_t q = 0; q < batch.queries.size(); ++q) {
                    const std::uint32_t g = batch.global[batch.queries[q]];
                    const float* d2 = batch.distance2.data() + q * k;
                    double sum = 0;
                    for (std::uint32_t j = 0; j < k; ++j) sum += std::sqrt(double(d2[j]));
                    mean_distance[g] = static_cast<float>(sum / k);
                    mth_distance[g] = std::sqrt(d2[r]);
                }
            },
            [&](std::uint64_t done) {
                progress.update(done);
                distances.drop();  // written at random: keep the resident set bounded
            });
        progress.finish();
    }
    distances.drop();
    if (params.sensor) {
        const auto& s = *params.sensor;
        auto range = [&](std::uint64_t i) {
            if ((i + 1) % k_drop_every == 0) {
                drop_pages(positions.data(), (i + 1) * sizeof positions[0]);
                distances.drop();
            }
            const auto& p = positions[i];
            return float(std::sqrt((p[0] - s[0]) * (p[0] - s[0]) + (p[1] - s[1]) * (p[1] - s[1]) +
                                   (p[2] - s[2]) * (p[2] - s[2])));
        };
        const double median_range = median_streamed(n, range);
        if (median_range > 0 && std::isfinite(median_range)) {
            for (std::uint64_t i = 0; i < n; ++i) {
                const double scale = median_range / std::max<double>(range(i), 1e-3 * median_range);
                mean_distance[i] = float(mean_distance[i] * scale);
                mth_distance[i] = float(mth_distance[i] * scale);
            }
            report.range_scaled = true;
        }
    }
    drop_pages(positions.data(), n * sizeof positions[0]);
    distances.drop();
    double sum = 0, sum2 = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        const float d = mean_distance[i];
        sum += d;
        sum2 += double(d) * d;
    }
    report.mean = sum / double(n);
    const double variance = std::max(0.0, (sum2 - sum * sum / double(n)) / double(n - 1));
    report.stddev = std::sqrt(variance);
    report.threshold = report.mean + params.std_ratio * report.stddev;
    report.median_spacing = median_streamed(n, [&](std::uint64_t i) {
        if ((i + 1) % k_drop_every == 0) distances.drop();
        return mean_distance[i];
    });
    report.radius_used = params.radius_factor * report.median_spacing;
    report.ran = true;
    for (std::uint64_t i = 0; i < n; ++i) {
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
    report.seconds = tool::now_seconds() - t0;
}

/// What the --grazing-cos step did (import.cpp normals_for()).
struct GrazingResult {
    std::uint64_t unsure = 0;   ///< normals below --grazing-cos to their line of sight
    std::uint64_t flipped = 0;  ///< of those, flipped by the propagation
};

/// normals_for()'s --grazing-cos step out of core: the normals more than acos(grazing_cos) from
/// their line of sight take their sign from the others by orient_by_propagation() with the others
/// fixed. Only the edges of the k-NN graph (k nearest, one tiled_knn() pass in the in-core kd-tree's
/// frame) that end at such a grazing normal take part (an edge to a fixed point is never followed),
/// so they are collected and put in the order of the in-core adjacency lists (by the edge's source
/// point, then its rank in that point's row), and propagate_signs() runs the same steps over them.
/// Needs those edges in memory (about 16 bytes each, up to 2k per grazing normal): throws, saying
/// to raise --memory, when they do not fit.
GrazingResult orient_grazing_tiled(std::span<const std::array<double, 3>> positions,
                                   std::span<pool::Float3> normals, std::span<const pool::Sensor> sensors,
                                   std::span<const std::uint16_t> scan_ids,
                                   std::span<const std::uint8_t> given, double grazing_cos, std::uint32_t k,
                                   const std::array<double, 3>& centre, const MemoryParams& memory,
                                   const Arrays& arrays, bool quiet, const std::string& label) {
    const std::uint64_t n = positions.size();
    GrazingResult result;
    // Per point: 0 no valid normal (no part), 1 fixed, 2 grazing.
    SpillFile state_file(memory.spill_folder, std::max<std::uint64_t>(n, 1), "the orientation states");
    const std::span<std::uint8_t> state = state_file.as<std::uint8_t>();
    std::uint64_t grazing = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        if (!given.empty() && given[i]) {  // the file's normal: a source
            state[i] = orient_detail::valid(normals[i]) ? 1 : 0;
            continue;
        }
        const pool::Sensor& sensor = sensors[scan_ids.empty() ? 0 : scan_ids[i]];
        double d[3];  // the line of sight (import.cpp's line_of_sight)
        for (int a = 0; a < 3; ++a)
            d[a] = sensor.kind == pool::k_sensor_direction ? sensor.position[a]
                                                           : sensor.position[a] - positions[i][a];
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const std::array<double, 3> l = {d[0] / len, d[1] / len, d[2] / len};
        const pool::Float3& m = normals[i];
        const bool fixed = std::fabs(m.x * l[0] + m.y * l[1] + m.z * l[2]) >= grazing_cos;
        result.unsure += !fixed;
        state[i] = !orient_detail::valid(m) ? 0 : fixed ? 1 : 2;
        grazing += state[i] == 2;
        if ((i + 1) % k_drop_every == 0) {
            arrays.drop();
            state_file.drop();
        }
    }
    if (grazing == 0) return result;  // nothing to propagate to (no part changes sign)

    std::vector<GrazingEdge> edges;
    const std::uint64_t limit = std::max<std::uint64_t>(memory.memory / 2 / sizeof(GrazingEdge), 1024);
    auto too_big = [&] {
        return Error(label + ": --grazing-cos " + fmt("%g", grazing_cos) + ": the " +
                     std::to_string(grazing) +
                     " grazing normals take their sign over the k-NN graph around them, more than --memory " +
                     tool::format_bytes(memory.memory) + " holds: raise --memory (or give --grazing-cos 0)");
    };
    {
        const SpillFile offsets = float_offsets(positions, centre, memory);
        tool::Progress progress("prt-import: grazing normals, k-NN by tiles (k=" + std::to_string(k) + ")", n,
                                quiet);
        tiled_knn(
            offsets.as<const pool::Float3>(), tiling_of(memory, k),
            [&](const KnnBatch& batch) {
                std::vector<std::uint32_t> row(k);
                for (std::size_t q = 0; q < batch.queries.size(); ++q) {
                    for (std::uint32_t j = 0; j < k; ++j) row[j] = batch.global[batch.neighbours[q * k + j]];
                    add_grazing_edges(batch.global[batch.queries[q]], row.data(), k, state, edges);
                    if (edges.size() > limit) throw too_big();
                }
            },
            [&](std::uint64_t done) {
                progress.update(done);
                state_file.drop();
                arrays.drop();
            });
        progress.finish();
    }
    result.flipped = propagate_grazing(
        std::move(edges), state, normals, [&](std::uint32_t g) { return positions[g][2]; }, memory.memory / 2,
        [&] { throw too_big(); }, quiet);
    arrays.drop();
    return result;
}

/// orient_by_propagation() over the whole k-NN graph out of core (normals estimated without a
/// sensor, Hoppe 1992 sec. 3.3): the graph's rows from one tiled_knn() pass go to a spill file by
/// point, the symmetric adjacency lists are built from them in two passes in point order exactly as
/// orient_by_propagation() builds them (spill files too), and propagate_signs() runs over them with
/// its per-point arrays in spill files: the same steps, so the same signs. Semi-external: every
/// array is a file mapping whose pages are dropped as the passes go (about 4k + 8k + 25 bytes per
/// point on disk); the propagation's random access makes it slow when they exceed the page cache.
OrientStats orient_by_propagation_tiled(std::span<const std::array<double, 3>> positions,
                                        std::span<pool::Float3> normals, std::span<const std::uint8_t> fixed,
                                        std::uint32_t k, const std::array<double, 3>& centre,
                                        const MemoryParams& memory, const Arrays& arrays, bool quiet) {
    const std::uint64_t n = positions.size();
    OrientStats stats;
    SpillFile rows_file(memory.spill_folder, std::max<std::uint64_t>(n * k, 1) * 4, "the k-NN graph");
    rows_file.advise_random();  // written by point as the tiles come
    const std::span<std::uint32_t> rows = rows_file.as<std::uint32_t>();
    {
        const SpillFile offsets = float_offsets(positions, centre, memory);
        tool::Progress progress("prt-import: orientation graph, k-NN by tiles (k=" + std::to_string(k) + ")",
                                n, quiet);
        tiled_knn(
            offsets.as<const pool::Float3>(), tiling_of(memory, k),
            [&](const KnnBatch& batch) {
                for (std::size_t q = 0; q < batch.queries.size(); ++q) {
                    const std::uint32_t g = batch.global[batch.queries[q]];
                    for (std::uint32_t j = 0; j < k; ++j)
                        rows[std::size_t(g) * k + j] = batch.global[batch.neighbours[q * k + j]];
                }
            },
            [&](std::uint64_t done) {
                progress.update(done);
                rows_file.drop();
                arrays.drop();
            });
        progress.finish();
    }
    rows_file.drop();
    return orient_over_rows(
        rows.subspan(0, n * k), k, normals, fixed, [&](std::uint32_t v) { return positions[v][2]; },
        memory.spill_folder,
        [&] {
            rows_file.drop();
            arrays.drop();
        },
        quiet);
}

}  // namespace

OrientStats orient_over_rows(std::span<const std::uint32_t> rows, std::uint32_t k,
                             std::span<pool::Float3> normals, std::span<const std::uint8_t> fixed,
                             const std::function<double(std::uint32_t)>& height,
                             const std::filesystem::path& spill_folder, const std::function<void()>& drop,
                             bool quiet) {
    const std::uint64_t n = normals.size();
    OrientStats stats;
    MemoryParams memory;
    memory.spill_folder = spill_folder;
    // Every array here is read or written at random (the edges' far ends, the propagation's heap
    // order): single pages in the page cache, not large folios (SpillFile::advise_random).
    SpillFile ok_file(memory.spill_folder, std::max<std::uint64_t>(n, 1), "the orientation flags");
    ok_file.advise_random();
    const std::span<std::uint8_t> ok = ok_file.as<std::uint8_t>();
    for (std::uint64_t i = 0; i < n; ++i) {
        ok[i] = orient_detail::valid(normals[i]);
        if (!ok[i]) ++stats.skipped;
    }
    // The symmetric adjacency (CSR), orient_by_propagation()'s each_edge in point order.
    SpillFile begin_file(memory.spill_folder, (n + 1) * 8, "the adjacency offsets");
    begin_file.advise_random();
    const std::span<std::uint64_t> begin = begin_file.as<std::uint64_t>();
    const SpillFile* pages = nullptr;  // the adjacency lists and their fill, once they exist
    const SpillFile* fill_pages = nullptr;
    auto each_edge = [&](auto&& fn) {
        for (std::uint64_t i = 0; i < n; ++i) {
            if (ok[i])
                for (std::uint32_t j = 0; j < k; ++j) {
                    const std::uint32_t m = rows[i * k + j];
                    if (m == k_no_neighbour || m == i || m >= n || !ok[m]) continue;
                    fn(static_cast<std::uint32_t>(i), m);
                }
            if ((i + 1) % (k_drop_every / 16) == 0) {  // random writes: drop often
                drop();
                begin_file.drop();
                if (pages) pages->drop();
                if (fill_pages) fill_pages->drop();
            }
        }
    };
    std::fill(begin.begin(), begin.end(), std::uint64_t{0});
    each_edge([&](std::uint32_t a, std::uint32_t b) {
        ++begin[a + 1];
        ++begin[b + 1];
    });
    for (std::uint64_t i = 0; i < n; ++i) begin[i + 1] += begin[i];
    SpillFile adjacent_file(memory.spill_folder, std::max<std::uint64_t>(begin[n], 1) * 4,
                            "the adjacency lists");
    adjacent_file.advise_random();
    const std::span<std::uint32_t> adjacent = adjacent_file.as<std::uint32_t>().subspan(0, begin[n]);
    pages = &adjacent_file;
    {
        SpillFile fill_file(memory.spill_folder, std::max<std::uint64_t>(n, 1) * 8, "the adjacency fill");
        fill_file.advise_random();
        const std::span<std::uint64_t> fill = fill_file.as<std::uint64_t>();
        fill_pages = &fill_file;
        std::copy(begin.begin(), begin.begin() + std::ptrdiff_t(n), fill.begin());
        each_edge([&](std::uint32_t a, std::uint32_t b) {
            adjacent[fill[a]++] = b;
            adjacent[fill[b]++] = a;
        });
        fill_pages = nullptr;
    }
    adjacent_file.drop();
    begin_file.drop();
    // propagate_signs() with its per-point arrays in one spill file.
    const std::uint64_t per = 1 + 4 + 8 + 4 + 4 + 4;
    SpillFile work(memory.spill_folder, std::max<std::uint64_t>(n, 1) * per + 64, "the orientation's arrays");
    work.advise_random();
    std::byte* w = work.data();
    auto carve = [&](auto* type, std::uint64_t bytes_each) {
        using T = std::remove_pointer_t<decltype(type)>;
        const std::span<T> s(reinterpret_cast<T*>(w), static_cast<std::size_t>(n));
        w += (n * bytes_each + 7) / 8 * 8;
        return s;
    };
    PropagationWorkspace ws;
    ws.pos = carve(static_cast<std::int64_t*>(nullptr), 8);
    ws.parent = carve(static_cast<std::uint32_t*>(nullptr), 4);
    ws.key = carve(static_cast<float*>(nullptr), 4);
    ws.heap = carve(static_cast<std::uint32_t*>(nullptr), 4);
    ws.order = carve(static_cast<std::uint32_t*>(nullptr), 4);
    ws.visited = carve(static_cast<std::uint8_t*>(nullptr), 1);
    ws.tick = [&] {
        work.drop();
        adjacent_file.drop();
        begin_file.drop();
        ok_file.drop();
        drop();
    };
    return propagate_signs(n, begin, adjacent, normals, ok.data(), fixed.empty() ? nullptr : fixed.data(),
                           height, quiet, nullptr, stats, &ws);
}

namespace {

Format point_format(const fs::path& path, const Options& options) {
    return options.format == Format::automatic ? detect_format(path) : options.format;
}

}  // namespace

void add_grazing_edges(std::uint32_t g, const std::uint32_t* row, std::uint32_t k,
                       std::span<const std::uint8_t> state, std::vector<GrazingEdge>& edges) {
    const std::uint8_t sg = state[g];
    if (sg == 0) return;
    for (std::uint32_t j = 0; j < k; ++j) {
        const std::uint32_t m = row[j];
        if (m == k_no_neighbour || m == g || m >= state.size() || state[m] == 0) continue;
        // The edge (g, m) is in g's list (as m) and in m's (as g), at g's turn: only what ends at
        // a grazing point is ever followed.
        if (state[m] == 2) edges.push_back({(std::uint64_t(g) << 32) | g, j, m});
        if (sg == 2) edges.push_back({(std::uint64_t(m) << 32) | g, j, g});
    }
}

std::uint64_t propagate_grazing(std::vector<GrazingEdge> edges, std::span<const std::uint8_t> state,
                                std::span<pool::Float3> normals,
                                const std::function<double(std::uint32_t)>& height_of, std::uint64_t memory,
                                const std::function<void()>& too_big, bool quiet) {
    std::sort(edges.begin(), edges.end(), [](const GrazingEdge& a, const GrazingEdge& b) {
        return a.key != b.key ? a.key < b.key : a.j < b.j;
    });
    // The vertices: every owner of a list and every grazing point (a lone one is a seed), in point order.
    std::vector<std::uint32_t> vertices;
    for (std::size_t i = 0; i < state.size(); ++i)
        if (state[i] == 2) vertices.push_back(static_cast<std::uint32_t>(i));
    for (const GrazingEdge& e : edges) vertices.push_back(static_cast<std::uint32_t>(e.key >> 32));
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    const std::size_t nv = vertices.size();
    if (nv * 40 + edges.size() * 4 > memory) too_big();
    auto local = [&](std::uint32_t g) {
        return static_cast<std::uint32_t>(std::lower_bound(vertices.begin(), vertices.end(), g) -
                                          vertices.begin());
    };
    std::vector<std::uint64_t> begin(nv + 1, 0);
    std::vector<std::uint32_t> adjacent(edges.size());
    {
        std::size_t v = 0;
        for (std::size_t e = 0; e < edges.size(); ++e) {
            const std::uint32_t owner = static_cast<std::uint32_t>(edges[e].key >> 32);
            while (vertices[v] != owner) begin[++v] = e;
            adjacent[e] = local(edges[e].target);
        }
        while (v < nv) begin[++v] = edges.size();
    }
    edges = {};
    std::vector<pool::Float3> local_normals(nv);
    std::vector<std::uint8_t> fixed(nv);
    std::vector<double> height(nv);
    for (std::size_t v = 0; v < nv; ++v) {
        local_normals[v] = normals[vertices[v]];
        fixed[v] = state[vertices[v]] == 1;
        height[v] = height_of(vertices[v]);
    }
    const OrientStats stats = propagate_signs(
        nv, begin, adjacent, local_normals, nullptr, fixed.data(), [&](std::uint32_t v) { return height[v]; },
        quiet, nullptr);
    for (std::size_t v = 0; v < nv; ++v)
        if (!fixed[v]) normals[vertices[v]] = local_normals[v];
    return stats.flipped;
}

void pool_input_report(const pool::PoolFile& file, const fs::path& path, Report& report) {
    const std::string label = path.string();
    report.records =
        file.find(pool::SectionType::positions) ? file.find(pool::SectionType::positions)->count : 0;
    report.reader = "pool";
    report.pools.push_back(path);
    std::string dropped;
    for (const pool::SectionEntry& e : file.sections()) {
        const auto t = static_cast<pool::SectionType>(e.type);
        using ST = pool::SectionType;
        if (t == ST::provenance || t == ST::model_info || t == ST::positions || t == ST::normals ||
            t == ST::colors || t == ST::intensities || t == ST::sensors || t == ST::scan_ids)
            continue;
        dropped += (dropped.empty() ? "" : ", ") + std::string(e.name, strnlen(e.name, sizeof e.name));
    }
    if (!dropped.empty())
        report.notes.push_back(label + ": not carried over: " + dropped +
                               " (computed again by the later steps: prt-radii, prt-octree, ...)");
    const auto sensors = file.array<pool::Sensor>(pool::SectionType::sensors);
    if (!sensors.empty())
        report.sensor_source = "the pool's sensors section (" + std::to_string(sensors.size()) + ")";
}

float median_streamed(std::uint64_t n, const std::function<float(std::uint64_t)>& value) {
    if (n == 0) return 0;
    const std::uint64_t rank = (n - 1) / 2;
    // Non-negative floats (and +inf) order as their bit patterns: select the high 16 bits, then
    // the low 16 bits among the values with those.
    std::vector<std::uint64_t> hist(65536);
    for (std::uint64_t i = 0; i < n; ++i) ++hist[std::bit_cast<std::uint32_t>(value(i)) >> 16];
    std::uint64_t below = 0;
    std::uint32_t high = 0;
    while (below + hist[high] <= rank) below += hist[high++];
    std::fill(hist.begin(), hist.end(), 0);
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint32_t bits = std::bit_cast<std::uint32_t>(value(i));
        if ((bits >> 16) == high) ++hist[bits & 0xFFFF];
    }
    std::uint32_t low = 0;
    while (below + hist[low] <= rank) below += hist[low++];
    return std::bit_cast<float>((high << 16) | low);
}

ImportEstimate estimate_import(const fs::path& path, const Options& options, bool sensor_given) {
    ImportEstimate e;
    const std::string label = path.string();
    const Format format = point_format(path, options);
    std::error_code ec;
    const std::uint64_t file_bytes = fs::file_size(path, ec);
    if (ec) throw Error(label + ": cannot open: " + ec.message());
    bool has_normals = false, has_sensor = false;
    // Bytes per point of the in-core import: the point set (positions, normals, colours,
    // intensities), clean()'s keys and flags, the kd-tree, the k-NN graph, PCA normals and the
    // orientation's adjacency (neighbours.cpp, orient_normals.cpp).
    std::uint64_t per_point = 24 + 12 + 8 + 16 + 2 + 32 + 8;
    const std::uint64_t k = static_cast<std::uint64_t>(options.k);
    if (format == Format::ply) {
        const MappedFile file = MappedFile::open(path);
        const PlyHeader header = parse_ply_header(file.view(), label);
        const PlyElement* vertex = header.find("vertex");
        e.points = vertex ? vertex->count : 0;
        has_normals = header.has_vertex_normals();
        const PlyElement* camera = header.find("camera");
        has_sensor = camera && camera->find("view_px") && camera->count == 1;
        if (options.mesh_mode == MeshMode::mesh || options.sample > 0 ||
            (options.mesh_mode == MeshMode::automatic && header.face_count() > 0 && !has_normals &&
             have_openmesh()))
            e.unsupported =
                label +
                ": a mesh (faces) is not imported out of core (--mesh-mode points reads its vertices)";
    } else if (format == Format::xyz) {
        const MappedFile file = MappedFile::open(path);
        const char* p = file.data();
        const char* const end = p + file.size();
        std::uint64_t lines = 0;
        while (p < end) {
            const char* eol =
                static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
            ++lines;
            p = eol ? eol + 1 : end;
        }
        e.points = lines;
        // The column count: the first line with 3 or 6 numbers (as read_xyz() fixes it).
        p = file.data();
        for (int tries = 0; p < end && tries < 1000; ++tries) {
            const char* eol =
                static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
            if (!eol) eol = end;
            std::string line(p, static_cast<std::size_t>(eol - p));
            if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
            for (char& c : line)
                if (c == ',' || c == ';' || c == '\t' || c == '\r') c = ' ';
            int fields = 0;
            for (std::size_t i = 0; i < line.size();) {
                while (i < line.size() && line[i] == ' ') ++i;
                if (i == line.size()) break;
                ++fields;
                while (i < line.size() && line[i] != ' ') ++i;
            }
            if (fields == 3 || fields == 6) {
                has_normals = fields == 6;
                break;
            }
            p = eol + 1;
        }
        drop_mapped_pages(file.data(), file.size());
    } else if (format == Format::pool) {
        const pool::PoolFile file = pool::PoolFile::open(path);
        const pool::SectionEntry* positions = file.find(pool::SectionType::positions);
        e.points = positions ? positions->count : 0;
        has_normals = file.has(pool::SectionType::normals);
        const auto sensors = file.array<pool::Sensor>(pool::SectionType::sensors);
        has_sensor = !sensors.empty();
        if (sensors.size() > 1 && file.has(pool::SectionType::scan_ids))
            e.unsupported = label + ": a pool of several scans (scan_ids) is not imported out of core";
        drop_mapped_pages(file.file_bytes().data(), file.file_bytes().size());
    } else {
        // PCD: the header's point count; pools and meshes: from the size (a pool holds at least 12
        // bytes of position per point, a mesh file about 24 bytes per vertex or more with faces).
        e.points = file_bytes / 24;
        if (format == Format::pcd) {
            const MappedFile file = MappedFile::open(path);
            Report unused;
            try {
                e.points = check_pcd(file, unused).points;
            } catch (const Error&) {
                // a bad header: the in-core import says what is wrong
            }
            drop_mapped_pages(file.data(), file.size());
        }
        e.unsupported = label + ": " + (format == Format::pcd ? std::string("PCD") : std::string("a mesh")) +
                        " is not imported out of core (only PLY, XYZ and pool point sets are)";
    }
    if (sensor_given) has_sensor = true;
    if (options.no_sensor) has_sensor = false;
    if (options.sensor || options.sensor_direction) has_sensor = true;
    const bool estimate = options.normals == NormalsMode::estimate ||
                          (options.normals == NormalsMode::automatic && !has_normals);
    // Meshes: vertices with area-weighted normals (OpenMesh's vertex and face records), no k-NN.
    const bool mesh = format == Format::mesh || (format == Format::ply && !e.unsupported.empty());
    if (mesh) {
        e.bytes = e.points * (per_point + 96);
        return e;
    }
    if (options.outliers.enabled || estimate)
        per_point += 4 * std::max<std::uint64_t>(options.outliers.k, estimate ? k : 0);
    if (estimate) per_point += 12 + 8 + 24;
    if (estimate && (!has_sensor || options.grazing_cos > 0 || options.propagate_then_vote))
        per_point += 8 * k + 24;  // orientation by propagation: the symmetric adjacency, heap, flags
    e.bytes = e.points * per_point;
    if (e.unsupported.empty() && estimate && options.propagate_then_vote)
        e.unsupported = label + ": orientation by propagation then vote is not out of core";
    return e;
}

namespace {

/// read_point_sections() of a pool of one scan in chunks (the radii, stale once points go, are
/// not read); the mapped pool's pages leave the resident set after each chunk.
PointCloud read_pool_chunks(const fs::path& path, Report& report, std::size_t chunk,
                            const std::function<void(const PointCloud&)>& flush) {
    const pool::PoolFile file = pool::PoolFile::open(path);
    const pool::ModelInfo& info = file.model_info();
    const auto pos = file.require<pool::Float3>(pool::SectionType::positions, "reading points");
    const auto nrm = file.array<pool::Float3>(pool::SectionType::normals);
    const auto col = file.array<pool::Rgba8>(pool::SectionType::colors);
    const auto inten = file.array<float>(pool::SectionType::intensities);
    pool_input_report(file, path, report);
    PointCloud c;
    for (std::size_t begin = 0; begin < pos.size(); begin += chunk) {
        const std::size_t end = std::min(pos.size(), begin + chunk);
        c.positions.resize(end - begin);
        for (std::size_t i = begin; i < end; ++i)
            c.positions[i - begin] = {info.origin[0] + pos[i].x, info.origin[1] + pos[i].y,
                                      info.origin[2] + pos[i].z};
        if (!nrm.empty())
            c.normals.assign(nrm.begin() + std::ptrdiff_t(begin), nrm.begin() + std::ptrdiff_t(end));
        if (!col.empty())
            c.colors.assign(col.begin() + std::ptrdiff_t(begin), col.begin() + std::ptrdiff_t(end));
        if (!inten.empty())
            c.intensities.assign(inten.begin() + std::ptrdiff_t(begin), inten.begin() + std::ptrdiff_t(end));
        flush(c);
        drop_mapped_pages(file.file_bytes().data(), file.file_bytes().size());
    }
    PointCloud head;
    const auto sensors = file.array<pool::Sensor>(pool::SectionType::sensors);
    head.sensors.assign(sensors.begin(), sensors.end());
    head.flags = info.flags;
    return head;
}

/// One scan read, cleaned and rid of outliers out of core (import.cpp read_scan() + prepare_scan()
/// up to the pose), in its own frame.
struct ScanStage {
    Arrays arrays;
    std::vector<pool::Sensor> sensors;  ///< the file's (or the pose list's) sensor, scan frame
    std::array<double, 3> centre{};     ///< the in-core kd-tree's centre (after clean())
    std::string peaks;                  ///< peak RSS per phase, for the note
};

/// `sensor_override`: the pose list names the scan's sensor (none when it holds no value).
ScanStage read_and_filter(const fs::path& path, const Options& options, const MemoryParams& memory,
                          Report& report, const std::optional<std::optional<pool::Sensor>>& sensor_override) {
    const std::string label = path.string();
    const ImportEstimate sizes = estimate_import(path, options, sensor_override && *sensor_override);
    if (!sizes.unsupported.empty()) throw Error(sizes.unsupported);
    report.label = label;
    const bool quiet = options.quiet;
    const double t0 = tool::now_seconds();
    const Format format = point_format(path, options);
    const bool drop_file_normals = options.normals == NormalsMode::estimate;
    const std::uint64_t capacity = std::max<std::uint64_t>(sizes.points, 1);

    // 1. Read in chunks: --keep-fraction, then clean()'s per-point checks; survivors to spill files.
    ScanStage stage;
    Arrays& arrays = stage.arrays;
    SpilledCloud& out = arrays.cloud;
    CleanReport& clean = report.clean;
    std::uint64_t record = 0;
    bool first = true;
    const std::size_t chunk = static_cast<std::size_t>(
        std::clamp<std::uint64_t>(memory.memory / 8 / 64, 4096, std::uint64_t{1} << 22));
    auto flush = [&](const PointCloud& c) {
        if (first) {
            first = false;
            out.positions = make_spill<std::array<double, 3>>(memory, capacity, "the positions");
            arrays.normals = c.has_normals() && !drop_file_normals;
            arrays.colors = c.has_colors();
            arrays.radii = c.has_radii();
            arrays.intensities = c.has_intensities();
            if (arrays.normals) out.normals = make_spill<pool::Float3>(memory, capacity, "the normals");
            if (arrays.colors) out.colors = make_spill<pool::Rgba8>(memory, capacity, "the colours");
            if (arrays.radii) out.radii = make_spill<float>(memory, capacity, "the radii");
            if (arrays.intensities) out.intensities = make_spill<float>(memory, capacity, "the intensities");
        }
        if (out.size + c.size() > capacity) throw Error(label + ": more points than the file announced");
        const auto p = out.positions.span();
        const auto nn = out.normals.span();
        for (std::size_t j = 0; j < c.size(); ++j, ++record) {
            if (options.keep_fraction < 1.0 &&
                !decimation_keeps(record, options.keep_fraction, options.seed)) {
                ++report.decimated;
                continue;
            }
            ++clean.input;
            const auto& q = c.positions[j];
            if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) {
                ++clean.non_finite;
                continue;
            }
            const std::uint64_t i = out.size;
            if (arrays.normals) {
                const pool::Float3 m = c.normals[j];
                const double len = std::sqrt(double(m.x) * m.x + double(m.y) * m.y + double(m.z) * m.z);
                if (!std::isfinite(len) || len < 1e-20) {
                    ++clean.zero_normal;
                    continue;
                }
                nn[i] = {float(m.x / len), float(m.y / len), float(m.z / len)};
            }
            p[i] = q;
            if (arrays.colors) out.colors.span()[i] = c.colors[j];
            if (arrays.radii) out.radii.span()[i] = c.radii[j];
            if (arrays.intensities) out.intensities.span()[i] = c.intensities[j];
            ++out.size;
        }
        arrays.drop();
    };
    bool file_normals = false;  // the file has normals (NormalsMode::estimate drops them)
    auto flush_first = [&](const PointCloud& c) {
        if (first) file_normals = c.has_normals();
        flush(c);
    };
    PointCloud head = format == Format::ply   ? read_ply_chunks(path, report, quiet, chunk, flush_first)
                      : format == Format::xyz ? read_xyz_chunks(path, report, quiet, chunk, flush_first)
                                              : read_pool_chunks(path, report, chunk, flush_first);
    if (drop_file_normals && file_normals)
        head.flags &= ~static_cast<std::uint32_t>(pool::k_model_normals_estimated);
    report.read_seconds = tool::now_seconds() - t0;
    stage.peaks = "peak RSS: read " + tool::format_bytes(peak_rss_bytes());
    if (first) out.positions = make_spill<std::array<double, 3>>(memory, 1, "the positions");
    if (arrays.normals) {
        report.normals_from_file = true;
        report.normals_detail = "from the file";
    }
    out.flags = head.flags;
    if (sensor_override) {
        head.sensors.clear();
        if (*sensor_override) head.sensors.push_back(**sensor_override);
    }
    if (options.no_sensor) head.sensors.clear();
    report.notes.push_back(label + ": out of core: the in-core import needs about " +
                           tool::format_bytes(sizes.bytes) + ", --memory is " +
                           tool::format_bytes(memory.memory) + "; spill files in " +
                           (memory.spill_folder.empty() ? std::string(".") : memory.spill_folder.string()));

    // 2. Exact duplicates (clean()), then the outliers of the scan.
    SpillFile keep_file(memory.spill_folder, std::max<std::uint64_t>(out.size, 1), "the point flags");
    auto keep = [&] { return keep_file.as<std::uint8_t>().subspan(0, out.size); };
    if (!options.keep_duplicates && out.size > 1) {
        std::fill(keep().begin(), keep().end(), std::uint8_t{1});
        clean.duplicates = drop_duplicates(out.positions.span().subspan(0, out.size), *out.positions.file,
                                           keep(), memory, quiet);
        if (clean.duplicates) arrays.compact(keep());
    }
    clean.kept = out.size;
    stage.peaks += ", duplicates " + tool::format_bytes(peak_rss_bytes());
    if (out.size == 0) throw Error(label + ": no points left: " + clean.summary());
    stage.centre = box_centre(out.positions.span().subspan(0, out.size));
    OutlierParams params = options.outliers;
    if (head.sensors.size() == 1 && head.sensors[0].kind == pool::k_sensor_point)
        params.sensor = std::array<double, 3>{head.sensors[0].position[0], head.sensors[0].position[1],
                                              head.sensors[0].position[2]};
    std::fill(keep().begin(), keep().end(), std::uint8_t{1});
    try {
        remove_outliers_tiled(out.positions.span().subspan(0, out.size), stage.centre, params, keep(),
                              report.outliers, memory, quiet);
    } catch (const Error& e) {
        throw Error(label + ": " + e.what());
    }
    if (report.outliers.removed) arrays.compact(keep());
    if (out.size == 0) throw Error(label + ": no points left after outlier removal");
    stage.peaks += ", outliers " + tool::format_bytes(peak_rss_bytes());
    stage.sensors = std::move(head.sensors);
    return stage;
}

/// --sensor / --sensor-direction replace the sensors (import.cpp finish()).
void command_line_sensor(const Options& options, SpilledCloud& out, bool& scan_ids) {
    if (options.sensor) {
        out.sensors = {pool::Sensor{
            {(*options.sensor)[0], (*options.sensor)[1], (*options.sensor)[2]}, pool::k_sensor_point, 0}};
        scan_ids = false;
    } else if (options.sensor_direction) {
        const auto& d = *options.sensor_direction;
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(len > 0) || !std::isfinite(len))
            throw Error("--sensor-direction must be a finite non-zero vector");
        out.sensors = {pool::Sensor{{d[0] / len, d[1] / len, d[2] / len}, pool::k_sensor_direction, 0}};
        scan_ids = false;
    }
    if (out.sensors.size() == 1) scan_ids = false;  // POOL.md: absent with one sensor
}

/// import.cpp normals_for() out of core with a sensor per point: PCA by tiles (in the frame of the
/// kd-tree centred at `centre`), the file's normals kept where arrays.given says so, the others
/// toward their sensor, --grazing-cos, then clean()'s check of the normals.
void estimate_normals(Arrays& arrays, const Options& options, const MemoryParams& memory, Report& report,
                      const std::string& label, const std::array<double, 3>& centre) {
    SpilledCloud& out = arrays.cloud;
    const bool quiet = options.quiet;
    if (out.sensors.empty() && options.propagate_then_vote)
        throw Error(label + ": orientation by propagation then vote is not out of core");
    const double t1 = tool::now_seconds();
    const std::uint32_t k = static_cast<std::uint32_t>(options.k);
    if (out.size < 3)
        throw Error(label + ": too few points (" + std::to_string(out.size) + ") to estimate normals");
    // The file's normals (merged scans, some with normals) stay in their array; PCA writes a new one.
    const SpillArray<pool::Float3> file_normals = out.normals;
    out.normals = make_spill<pool::Float3>(memory, out.size, "the normals");
    if (out.sensors.empty()) out.normals.file->advise_random();  // the propagation reads them at random
    arrays.normals = true;
    const auto positions = out.positions.span().subspan(0, out.size);
    const auto normals = out.normals.span().subspan(0, out.size);
    {
        tool::Progress progress("prt-import: normals, k-NN by tiles (k=" + std::to_string(k) + ")", out.size,
                                quiet);
        try {
            pca_normals_tiled(
                positions, k, tiling_of(memory, k), normals, nullptr,
                [&](std::uint64_t done) {
                    progress.update(done);
                    arrays.drop();  // positions read and normals written at random
                },
                &centre);
        } catch (const Error& e) {
            throw Error(label + ": " + e.what());
        }
        progress.finish();
    }
    const std::span<const std::uint8_t> given =
        arrays.given.file ? std::span<const std::uint8_t>(arrays.given.span().subspan(0, out.size))
                          : std::span<const std::uint8_t>{};
    const std::span<const std::uint16_t> ids =
        arrays.scan_ids ? std::span<const std::uint16_t>(out.scan_ids.span().subspan(0, out.size))
                        : std::span<const std::uint16_t>{};
    std::uint64_t kept = 0, ambiguous = 0;
    for (std::uint64_t i = 0; i < out.size; ++i) {
        if (!given.empty() && given[i]) {
            normals[i] = file_normals.span()[i];
            ++kept;
        } else if (!out.sensors.empty()) {
            ambiguous +=
                orient_toward_one(positions[i], normals[i], out.sensors[ids.empty() ? 0 : ids[i]]) == 1;
        }
        if ((i + 1) % k_drop_every == 0) {
            arrays.drop();
            if (file_normals.file) file_normals.file->drop();
        }
    }
    std::string how;
    if (out.sensors.empty()) {
        // Without a sensor: propagation over the whole k-NN graph (orient_by_propagation()).
        OrientStats stats;
        try {
            stats = orient_by_propagation_tiled(positions, normals,
                                                kept > 0 ? given : std::span<const std::uint8_t>{}, k, centre,
                                                memory, arrays, quiet);
        } catch (const Error& e) {
            throw Error(label + ": " + e.what());
        }
        report.components = stats.components;
        report.ambiguous = stats.ambiguous;
        how =
            "oriented by propagation over the k-NN graph (Hoppe 1992): " +
            (kept > 0 ? "from the file's normals, then " : std::string()) + std::to_string(stats.components) +
            " components seeded at their highest point with +z outward; " + std::to_string(stats.ambiguous) +
            " ambiguous (|n_i . n_j| < 0.1 to every neighbour oriented before)";
    } else {
        how = (out.sensors.size() == 1 ? "oriented toward the sensor (" + sensor_text(out.sensors[0]) + ")"
                                       : "oriented toward each point's own sensor (" +
                                             std::to_string(out.sensors.size()) + " scans)") +
              "; " + std::to_string(ambiguous) +
              " ambiguous (grazing: normal within 5.7 degrees of perpendicular to the line of sight)";
    }
    if (options.grazing_cos > 0 && !out.sensors.empty()) {
        GrazingResult g;
        try {
            g = orient_grazing_tiled(positions, normals, out.sensors, ids, given, options.grazing_cos, k,
                                     centre, memory, arrays, quiet, label);
        } catch (const Error& e) {
            const std::string what = e.what();
            throw Error(what.rfind(label, 0) == 0 ? what : label + ": " + what);
        }
        report.grazing_flipped = g.flipped;
        how += "; the " + std::to_string(g.unsure) + " more than " +
               fmt("%.1f", std::acos(options.grazing_cos) * 180 / 3.14159265358979323846) +
               " degrees from their line of sight took their sign from the others over the k-NN graph (" +
               std::to_string(g.flipped) + " flipped)";
    }
    out.flags |= pool::k_model_normals_estimated;
    report.normals_estimated = true;
    if (!out.sensors.empty()) {
        report.oriented_to_sensor = true;
        report.ambiguous = ambiguous;
    }
    // clean(cloud, false): PCA's failures (no normal) go, the others are renormalised.
    SpillFile flag_file(memory.spill_folder, std::max<std::uint64_t>(out.size, 1), "the point flags");
    const auto flags = flag_file.as<std::uint8_t>();
    std::uint64_t failed = 0;
    for (std::uint64_t i = 0; i < out.size; ++i) {
        pool::Float3& m = normals[i];
        const double len = std::sqrt(double(m.x) * m.x + double(m.y) * m.y + double(m.z) * m.z);
        flags[i] = std::isfinite(len) && len >= 1e-20;
        if (flags[i])
            m = {float(m.x / len), float(m.y / len), float(m.z / len)};
        else
            ++failed;
        if ((i + 1) % k_drop_every == 0) arrays.drop();
    }
    if (failed) arrays.compact(flags);
    report.estimate_failed = failed;
    report.normals_seconds = tool::now_seconds() - t1;
    report.normals_detail =
        "estimated by PCA over k=" + std::to_string(options.k) + " neighbours in " +
        fmt("%.3f s", report.normals_seconds) +
        (kept ? " (" + std::to_string(kept) + " kept from the files)" : std::string()) + "; " + how +
        (failed
             ? "; " + std::to_string(failed) + " points without a normal (degenerate neighbourhood) dropped"
             : "");
    if (out.size == 0) throw Error(label + ": no points left after normal estimation");
}

std::string sensors_detail(const SpilledCloud& out, const Options& options, const std::string& source) {
    if (out.sensors.empty()) return "none";
    if (out.sensors.size() > 1)
        return std::to_string(out.sensors.size()) + " (one per scan), scan_ids per point";
    return "1 " + sensor_text(out.sensors[0]) +
           (options.sensor || options.sensor_direction ? " (command line)"
            : !source.empty()                          ? " (" + source + ")"
                                                       : std::string());
}

SpilledCloud finish_cloud(Arrays& arrays) {
    if (!arrays.normals) arrays.cloud.normals = {};
    if (!arrays.colors) arrays.cloud.colors = {};
    if (!arrays.radii) arrays.cloud.radii = {};
    if (!arrays.intensities) arrays.cloud.intensities = {};
    if (!arrays.scan_ids) arrays.cloud.scan_ids = {};
    return std::move(arrays.cloud);
}

}  // namespace

SpilledCloud import_file_out_of_core(const fs::path& path, const Options& options, const MemoryParams& memory,
                                     Report& report) {
    const std::string label = path.string();
    ScanStage stage = read_and_filter(path, options, memory, report, std::nullopt);
    Arrays& arrays = stage.arrays;
    SpilledCloud& out = arrays.cloud;
    out.sensors = std::move(stage.sensors);
    command_line_sensor(options, out, arrays.scan_ids);
    const bool estimate = options.normals != NormalsMode::keep && !arrays.normals;
    if (estimate) {
        estimate_normals(arrays, options, memory, report, label, stage.centre);
        stage.peaks += ", normals " + tool::format_bytes(peak_rss_bytes());
    } else if (!arrays.normals) {
        report.normals_detail =
            "none (the file has none and --normals keep): the pool has no normals section";
    }
    report.notes.push_back(label + ": out of core: " + stage.peaks);
    report.sensors_detail = sensors_detail(out, options, report.sensor_source);
    report.written = out.size;
    return finish_cloud(arrays);
}

SpilledCloud import_merged_out_of_core(const fs::path& poses, const std::vector<fs::path>& only,
                                       const Options& options, const MemoryParams& memory, Report& report) {
    std::vector<PoseEntry> entries = read_poses(poses, only);
    const std::string label = poses.string();
    if (entries.size() == 1 && entries[0].pose.is_identity())
        throw Error(label +
                    ": one scan at the identity pose is not merged out of core: import the scan itself");
    report.reader = "pose list " + label;
    // Each scan: read, cleaned and filtered in its own frame, then moved (import.cpp prepare_scan()).
    std::vector<ScanStage> scans;
    std::vector<Report> per(entries.size());
    for (std::size_t s = 0; s < entries.size(); ++s) {
        const PoseEntry& entry = entries[s];
        std::optional<std::optional<pool::Sensor>> sensor_override;
        if (entry.sensor_given) sensor_override = entry.sensor;
        scans.push_back(read_and_filter(entry.file, options, memory, per[s], sensor_override));
        if (entry.sensor_given) per[s].sensor_source = entry.where;
        ScanStage& st = scans.back();
        if (!entry.pose.is_identity()) {
            SpilledCloud& c = st.arrays.cloud;
            const auto p = c.positions.span();
            const auto nn = c.normals.span();
            for (std::uint64_t i = 0; i < c.size; ++i) {
                p[i] = entry.pose.apply(p[i]);
                if (st.arrays.normals) {
                    const auto r = entry.pose.rotate({nn[i].x, nn[i].y, nn[i].z});
                    nn[i] = {static_cast<float>(r[0]), static_cast<float>(r[1]), static_cast<float>(r[2])};
                }
                if ((i + 1) % k_drop_every == 0) st.arrays.drop();
            }
            st.arrays.drop();
            for (auto& sn : st.sensors) sn = entry.pose.apply(sn);
        }
    }
    for (const Report& r : per) report.pools.insert(report.pools.end(), r.pools.begin(), r.pools.end());
    // The merge (import.cpp finish()): attributes all scans have, sensors and scan_ids when every
    // scan has a sensor, the file's normals flagged when only some scans have them.
    bool all_normals = true, any_normals = false, all_sensors = true, any_sensor = false;
    bool colors = true, radii = true, intensities = true;
    std::uint64_t total = 0, sensor_total = 0;
    for (const ScanStage& st : scans) {
        all_normals = all_normals && st.arrays.normals;
        any_normals = any_normals || st.arrays.normals;
        all_sensors = all_sensors && !st.sensors.empty();
        any_sensor = any_sensor || !st.sensors.empty();
        colors = colors && st.arrays.colors;
        radii = radii && st.arrays.radii;
        intensities = intensities && st.arrays.intensities;
        total += st.arrays.cloud.size;
        sensor_total += st.sensors.size();
    }
    if (sensor_total > pool::k_max_sensors)
        throw Error(label + ": " + std::to_string(sensor_total) + " sensors, at most " +
                    std::to_string(pool::k_max_sensors) + " (scan_ids are 16-bit)");
    const bool mixed_normals = any_normals && !all_normals;
    Arrays arrays;
    SpilledCloud& out = arrays.cloud;
    out.positions = make_spill<std::array<double, 3>>(memory, total, "the merged positions");
    arrays.normals = any_normals;
    arrays.colors = colors;
    arrays.radii = radii;
    arrays.intensities = intensities;
    arrays.scan_ids = all_sensors;
    if (arrays.normals) out.normals = make_spill<pool::Float3>(memory, total, "the merged normals");
    if (colors) out.colors = make_spill<pool::Rgba8>(memory, total, "the merged colours");
    if (radii) out.radii = make_spill<float>(memory, total, "the merged radii");
    if (intensities) out.intensities = make_spill<float>(memory, total, "the merged intensities");
    if (all_sensors) out.scan_ids = make_spill<std::uint16_t>(memory, total, "the scan ids");
    if (mixed_normals) arrays.given = make_spill<std::uint8_t>(memory, total, "the normal flags");
    std::vector<std::string> dropped;
    auto note_dropped = [&](bool kept, bool any, const char* what) {
        if (!kept && any) dropped.push_back(what);
    };
    bool any_colors = false, any_radii = false, any_intensities = false;
    for (const ScanStage& st : scans) {
        any_colors = any_colors || st.arrays.colors;
        any_radii = any_radii || st.arrays.radii;
        any_intensities = any_intensities || st.arrays.intensities;
    }
    note_dropped(colors, any_colors, "colors");
    note_dropped(intensities, any_intensities, "intensities");
    note_dropped(radii, any_radii, "radii");
    std::uint64_t at = 0;
    for (ScanStage& st : scans) {
        const SpilledCloud& c = st.arrays.cloud;
        const std::uint16_t base = static_cast<std::uint16_t>(out.sensors.size());
        for (std::uint64_t i = 0; i < c.size; ++i, ++at) {
            out.positions.span()[at] = c.positions.span()[i];
            if (arrays.normals)
                out.normals.span()[at] =
                    st.arrays.normals ? c.normals.span()[i] : pool::Float3{0.f, 0.f, 1.f};
            if (mixed_normals) arrays.given.span()[at] = st.arrays.normals ? 1 : 0;
            if (colors) out.colors.span()[at] = c.colors.span()[i];
            if (radii) out.radii.span()[at] = c.radii.span()[i];
            if (intensities) out.intensities.span()[at] = c.intensities.span()[i];
            if (all_sensors) out.scan_ids.span()[at] = base;
            if ((i + 1) % k_drop_every == 0) {
                arrays.drop();
                st.arrays.drop();
            }
        }
        if (all_sensors) out.sensors.insert(out.sensors.end(), st.sensors.begin(), st.sensors.end());
        out.flags |= c.flags;
        arrays.drop();
        st.arrays = Arrays{};  // its spill files go
    }
    out.size = total;
    if (any_sensor && !all_sensors)
        report.notes.push_back(
            label + ": only some scans have a sensor: none recorded, normals oriented by propagation");
    for (const char* d : {"colors", "intensities", "radii"})
        if (std::find(dropped.begin(), dropped.end(), d) != dropped.end())
            report.notes.push_back(label + ": only some scans have " + d + ": dropped from the result");
    command_line_sensor(options, out, arrays.scan_ids);

    // Sums of the scans' counts, then clean() over the merged points: duplicates across scans.
    for (const Report& r : per) {
        report.records += r.records;
        report.nan_entries += r.nan_entries;
        report.malformed_lines += r.malformed_lines;
        report.outliers.input += r.outliers.input;
        report.outliers.removed += r.outliers.removed;
        report.outliers.statistical += r.outliers.statistical;
        report.outliers.radius += r.outliers.radius;
        report.outliers.seconds += r.outliers.seconds;
        report.outliers.ran = report.outliers.ran || r.outliers.ran;
        report.read_seconds += r.read_seconds;
    }
    CleanReport& clean = report.clean;
    clean.input = out.size;
    {
        SpillFile keep_file(memory.spill_folder, std::max<std::uint64_t>(out.size, 1), "the point flags");
        const auto keep = keep_file.as<std::uint8_t>().subspan(0, out.size);
        const auto p = out.positions.span();
        const auto nn = out.normals.span();
        for (std::uint64_t i = 0; i < out.size; ++i) {
            keep[i] = 1;
            if (!std::isfinite(p[i][0]) || !std::isfinite(p[i][1]) || !std::isfinite(p[i][2])) {
                keep[i] = 0;
                ++clean.non_finite;
            } else if (arrays.normals) {
                pool::Float3& m = nn[i];
                const double len = std::sqrt(double(m.x) * m.x + double(m.y) * m.y + double(m.z) * m.z);
                if (!std::isfinite(len) || len < 1e-20) {
                    keep[i] = 0;
                    ++clean.zero_normal;
                } else {
                    m = {float(m.x / len), float(m.y / len), float(m.z / len)};
                }
            }
            if ((i + 1) % k_drop_every == 0) arrays.drop();
        }
        if (!options.keep_duplicates && out.size > 1)
            clean.duplicates =
                drop_duplicates(p.subspan(0, out.size), *out.positions.file, keep, memory, options.quiet);
        if (clean.non_finite || clean.zero_normal || clean.duplicates) arrays.compact(keep);
        clean.kept = out.size;
    }
    if (mixed_normals) {
        if (options.normals != NormalsMode::keep)
            report.notes.push_back(label + ": only some scans have normals: the others' are estimated");
        else {
            arrays.normals = false;
            report.notes.push_back(label +
                                   ": only some scans have normals and --normals keep: the result has none");
        }
    }
    const bool estimate = options.normals != NormalsMode::keep && !all_normals;
    if (estimate) {
        if (out.size == 0) throw Error(label + ": no points left");
        const std::array<double, 3> centre = box_centre(out.positions.span().subspan(0, out.size));
        estimate_normals(arrays, options, memory, report, label, centre);
    } else if (!arrays.normals) {
        report.normals_detail =
            "none (the file has none and --normals keep): the pool has no normals section";
    } else {
        report.normals_detail = "from the files";
        report.normals_from_file = true;
    }
    std::string peaks;
    for (std::size_t s = 0; s < scans.size(); ++s) peaks += (s ? "; " : "") + scans[s].peaks;
    report.notes.push_back(label + ": out of core: " + peaks + "; merged " +
                           tool::format_bytes(peak_rss_bytes()));
    report.sensors_detail = sensors_detail(out, options, per.empty() ? std::string() : per[0].sensor_source);
    report.written = out.size;
    report.scans = std::move(per);
    return finish_cloud(arrays);
}

void write_point_sections(const SpilledCloud& cloud, const MemoryParams& memory, pool::PoolWriter& writer) {
    if (cloud.size == 0)
        throw Error("no points to write (every input point was dropped or the input is empty)");
    const auto positions = cloud.positions.span().subspan(0, cloud.size);
    std::array<double, 3> lo = positions[0], hi = positions[0];
    for (const auto& p : positions)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    pool::ModelInfo info{};
    for (int a = 0; a < 3; ++a) info.origin[a] = 0.5 * (lo[a] + hi[a]);
    auto local = std::make_shared<SpillFile>(memory.spill_folder, cloud.size * sizeof(pool::Float3),
                                             "the local positions");
    const auto l = local->as<pool::Float3>();
    for (std::uint64_t i = 0; i < cloud.size; ++i) {
        l[i] = {float(positions[i][0] - info.origin[0]), float(positions[i][1] - info.origin[1]),
                float(positions[i][2] - info.origin[2])};
        if ((i + 1) % k_drop_every == 0) {
            local->drop();
            cloud.positions.file->drop();
        }
    }
    cloud.positions.file->drop();
    pool::set_point_bounds(info, l);
    local->drop();
    info.flags = cloud.flags;
    writer.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
    auto view = [&](pool::SectionType type, const std::shared_ptr<SpillFile>& file,
                    std::uint32_t element_size) {
        if (!file) {
            writer.remove(type);
            return;
        }
        writer.add_view(type, element_size, cloud.size,
                        {file->data(), static_cast<std::size_t>(cloud.size * element_size)},
                        std::shared_ptr<const void>(file, file->data()), true);
    };
    view(pool::SectionType::positions, local, sizeof(pool::Float3));
    view(pool::SectionType::normals, cloud.normals.file, sizeof(pool::Float3));
    view(pool::SectionType::colors, cloud.colors.file, sizeof(pool::Rgba8));
    view(pool::SectionType::radii, cloud.radii.file, sizeof(float));
    view(pool::SectionType::intensities, cloud.intensities.file, sizeof(float));
    view(pool::SectionType::scan_ids, cloud.scan_ids.file, sizeof(std::uint16_t));
    if (!cloud.sensors.empty())
        writer.add_array(pool::SectionType::sensors, cloud.sensors);
    else
        writer.remove(pool::SectionType::sensors);
}

}  // namespace prt::pre::import
