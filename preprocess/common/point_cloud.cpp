#include "point_cloud.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>

#include "buffer.h"
#include "prt/parallel.h"
#include "radix_sort.h"

namespace prt::pre {

std::string CleanReport::summary() const {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "%llu points read, %llu kept; dropped %llu non-finite, %llu zero normals, %llu duplicates",
                  static_cast<unsigned long long>(input), static_cast<unsigned long long>(kept),
                  static_cast<unsigned long long>(non_finite), static_cast<unsigned long long>(zero_normal),
                  static_cast<unsigned long long>(duplicates));
    return buf;
}

std::size_t keep_points(PointCloud& cloud, const std::vector<std::uint8_t>& keep,
                        std::vector<std::size_t>* kept) {
    std::size_t out = 0;
    if (kept) kept->clear();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!keep[i]) continue;
        if (kept) kept->push_back(i);
        cloud.positions[out] = cloud.positions[i];
        if (cloud.has_normals()) cloud.normals[out] = cloud.normals[i];
        if (cloud.has_colors()) cloud.colors[out] = cloud.colors[i];
        if (cloud.has_radii()) cloud.radii[out] = cloud.radii[i];
        if (cloud.has_intensities()) cloud.intensities[out] = cloud.intensities[i];
        if (cloud.has_scan_ids()) cloud.scan_ids[out] = cloud.scan_ids[i];
        ++out;
    }
    cloud.positions.resize(out);
    if (cloud.has_normals()) cloud.normals.resize(out);
    if (cloud.has_colors()) cloud.colors.resize(out);
    if (cloud.has_radii()) cloud.radii.resize(out);
    if (cloud.has_intensities()) cloud.intensities.resize(out);
    if (cloud.has_scan_ids()) cloud.scan_ids.resize(out);
    return out;
}

std::uint64_t position_hash(const std::array<double, 3>& p) {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int a = 0; a < 3; ++a) {
        const double v = p[a] == 0.0 ? 0.0 : p[a];  // -0 == +0
        std::uint64_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        h = (h ^ bits) * 0xBF58476D1CE4E5B9ull;
        h ^= h >> 31;
    }
    return h;
}

CleanReport clean(PointCloud& cloud, bool drop_duplicates, std::vector<std::size_t>* kept) {
    CleanReport report;
    const std::size_t n = cloud.size();
    report.input = n;
    const unsigned threads = resolve_threads(0);
    std::vector<std::uint8_t> keep(n, 1);
    std::vector<std::array<std::uint64_t, 2>> dropped(threads, {0, 0});  // per worker: non-finite, zero normal
    parallel_chunks(n, 1 << 15, threads, [&](std::size_t b, std::size_t e, unsigned worker) {
        for (std::size_t i = b; i < e; ++i) {
            const auto& p = cloud.positions[i];
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
                keep[i] = 0;
                ++dropped[worker][0];
                continue;
            }
            if (cloud.has_normals()) {
                auto& nn = cloud.normals[i];
                const double len = std::sqrt(double(nn.x) * nn.x + double(nn.y) * nn.y + double(nn.z) * nn.z);
                if (!std::isfinite(len) || len < 1e-20) {
                    keep[i] = 0;
                    ++dropped[worker][1];
                    continue;
                }
                nn = {float(nn.x / len), float(nn.y / len), float(nn.z / len)};
            }
        }
    });
    for (const auto& d : dropped) report.non_finite += d[0], report.zero_normal += d[1];
    if (drop_duplicates && n > 1) {
        // Exact duplicates: sort (hash of the coordinate bits, index) pairs, then compare real
        // coordinates inside runs of equal hashes. Keeps the first occurrence in input order. The
        // pairs are made in index order and the radix sort is stable: sorted by (hash, index).
        struct Key {
            std::uint64_t hash;
            std::uint32_t index;
        };
        // The points still kept: those the checks above did not drop.
        Buffer<Key> keys(n - report.non_finite - report.zero_normal);  // first touched by the parallel fill
        parallel_select(n, threads, [&](std::size_t i) { return keep[i] != 0; },
                        [&](std::size_t rank, std::size_t i) {
                            keys[rank] = {position_hash(cloud.positions[i]), static_cast<std::uint32_t>(i)};
                        });
        radix_sort_by(keys, 64, threads, [](const Key& k) { return k.hash; });
        for (std::size_t run = 0; run < keys.size();) {
            std::size_t end = run + 1;
            while (end < keys.size() && keys[end].hash == keys[run].hash) ++end;
            for (std::size_t a = run; a < end; ++a) {
                if (!keep[keys[a].index]) continue;
                for (std::size_t b = a + 1; b < end; ++b)
                    if (keep[keys[b].index] &&
                        cloud.positions[keys[b].index] == cloud.positions[keys[a].index]) {
                        keep[keys[b].index] = 0;
                        ++report.duplicates;
                    }
            }
            run = end;
        }
    }
    report.kept = keep_points(cloud, keep, kept);
    return report;
}

std::array<std::array<double, 3>, 2> bounds(const PointCloud& cloud) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::array<std::array<double, 3>, 2> b{{{inf, inf, inf}, {-inf, -inf, -inf}}};
    for (const auto& p : cloud.positions)
        for (int a = 0; a < 3; ++a) {
            b[0][a] = std::min(b[0][a], p[a]);
            b[1][a] = std::max(b[1][a], p[a]);
        }
    return b;
}

void write_point_sections(const PointCloud& cloud, pool::PoolWriter& writer) {
    if (cloud.size() == 0)
        throw Error("no points to write (every input point was dropped or the input is empty)");
    const auto b = bounds(cloud);
    pool::ModelInfo info{};
    for (int a = 0; a < 3; ++a) info.origin[a] = 0.5 * (b[0][a] + b[1][a]);
    std::vector<pool::Float3> local(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        local[i] = {float(cloud.positions[i][0] - info.origin[0]), float(cloud.positions[i][1] - info.origin[1]),
                    float(cloud.positions[i][2] - info.origin[2])};
    pool::set_point_bounds(info, local);
    info.flags = cloud.flags;
    writer.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
    writer.add_array(pool::SectionType::positions, std::move(local));
    // Each optional section is written when the cloud has it and removed otherwise.
    const auto put = [&writer](pool::SectionType type, const auto& elements) {
        if (!elements.empty())
            writer.add_array(type, elements);
        else
            writer.remove(type);
    };
    put(pool::SectionType::normals, cloud.normals);
    put(pool::SectionType::colors, cloud.colors);
    put(pool::SectionType::radii, cloud.radii);
    put(pool::SectionType::intensities, cloud.intensities);
    put(pool::SectionType::sensors, cloud.sensors);
    put(pool::SectionType::scan_ids, cloud.scan_ids);
}

PointCloud read_point_sections(const pool::PoolFile& pool) {
    PointCloud cloud;
    const pool::ModelInfo& info = pool.model_info();
    const auto pos = pool.require<pool::Float3>(pool::SectionType::positions, "reading points");
    cloud.positions.resize(pos.size());
    for (std::size_t i = 0; i < pos.size(); ++i)
        cloud.positions[i] = {info.origin[0] + pos[i].x, info.origin[1] + pos[i].y,
                              info.origin[2] + pos[i].z};
    const auto nrm = pool.array<pool::Float3>(pool::SectionType::normals);
    cloud.normals.assign(nrm.begin(), nrm.end());
    const auto col = pool.array<pool::Rgba8>(pool::SectionType::colors);
    cloud.colors.assign(col.begin(), col.end());
    const auto rad = pool.array<float>(pool::SectionType::radii);
    cloud.radii.assign(rad.begin(), rad.end());
    const auto inten = pool.array<float>(pool::SectionType::intensities);
    cloud.intensities.assign(inten.begin(), inten.end());
    const auto ids = pool.array<std::uint16_t>(pool::SectionType::scan_ids);
    cloud.scan_ids.assign(ids.begin(), ids.end());
    const auto sensors = pool.array<pool::Sensor>(pool::SectionType::sensors);
    cloud.sensors.assign(sensors.begin(), sensors.end());
    cloud.flags = info.flags;
    return cloud;
}

}  // namespace prt::pre
