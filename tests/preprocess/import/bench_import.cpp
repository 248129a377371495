// prt-bench-import: times PLY import of a generated binary point set with normals (default 1M
// points): our reader, our whole import (read + clean, without and with the default outlier
// removal, + pool write), PCL's PLYReader and OpenMesh's reader (when the build has them). Median
// and minimum of --repeat runs after one warm-up run (the file is in the page cache: this measures
// parsing, not the disk). Output: one table row per reader.
#include "bench_import.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "import.h"
#include "ply_reader.h"
#include "prt/formats/pool.h"
#include "prt/tool.h"

namespace fs = std::filesystem;
namespace imp = prt::pre::import;

namespace {

/// Binary little-endian PLY: float x y z nx ny nz, points uniform in a cube, unit normals.
void generate(const fs::path& path, std::uint64_t n) {
    std::string header =
        "ply\nformat binary_little_endian 1.0\ncomment prt-bench-import\nelement vertex " +
        std::to_string(n) +
        "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float "
        "ny\nproperty float nz\nend_header\n";
    std::ofstream out(path, std::ios::binary);
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    std::vector<float> row(6 * 4096);
    for (std::uint64_t done = 0; done < n;) {
        const std::uint64_t m = std::min<std::uint64_t>(4096, n - done);
        for (std::uint64_t i = 0; i < m; ++i) {
            float* r = &row[6 * i];
            r[0] = u(rng);
            r[1] = u(rng);
            r[2] = u(rng);
            float len = 0;
            do {
                r[3] = u(rng);
                r[4] = u(rng);
                r[5] = u(rng);
                len = std::sqrt(r[3] * r[3] + r[4] * r[4] + r[5] * r[5]);
            } while (len < 0.1f || len > 1.f);
            r[3] /= len;
            r[4] /= len;
            r[5] /= len;
        }
        out.write(reinterpret_cast<const char*>(row.data()),
                  static_cast<std::streamsize>(m * 6 * sizeof(float)));
        done += m;
    }
    if (!out) throw prt::Error(path.string() + ": cannot write the benchmark file");
}

struct Result {
    std::string name;
    double median = 0, min = 0;
    std::uint64_t points = 0;
};

Result time_it(const std::string& name, int repeat, const std::function<std::uint64_t()>& fn) {
    Result r{name, 0, 0, fn()};  // warm-up (page cache, allocator)
    std::vector<double> t;
    for (int i = 0; i < repeat; ++i) {
        const double t0 = prt::tool::now_seconds();
        r.points = fn();
        t.push_back(prt::tool::now_seconds() - t0);
    }
    std::sort(t.begin(), t.end());
    r.median = t[t.size() / 2];
    r.min = t.front();
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    std::uint64_t points = 1000000;
    std::string file;
    int repeat = 5;
    return prt::tool::run(
        argc, argv, "prt-bench-import", "Times PLY readers on a generated binary PLY with normals",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("--points", points, "Points in the generated file");
            app.add_option("--file", file,
                           "PLY to generate (kept and reused when its size matches); default: a "
                           "temporary file, removed afterwards");
            app.add_option("--repeat", repeat, "Timed runs per reader (after one warm-up)")
                ->check(CLI::Range(1, 100));
        },
        [&](const prt::tool::CommonOptions& common) {
            const bool temporary = file.empty();
            const fs::path path = temporary ? fs::temp_directory_path() /
                                                  ("prt_bench_import_" + std::to_string(points) + ".ply")
                                            : fs::path(file);
            const std::uint64_t expected_size = 6 * 4 * points;
            if (!fs::exists(path) || fs::file_size(path) < expected_size) {
                prt::tool::note(common.quiet, "generating %s (%llu points)", path.string().c_str(),
                                static_cast<unsigned long long>(points));
                generate(path, points);
            }
            const fs::path pool_path = fs::temp_directory_path() / "prt_bench_import.pool";
            std::vector<Result> results;
            results.push_back(time_it("prt read_ply (reader only)", repeat, [&] {
                imp::Report report;
                return static_cast<std::uint64_t>(imp::read_ply(path, report, true).size());
            }));
            results.push_back(time_it("prt import_file (--keep-outliers)", repeat, [&] {
                imp::Report report;
                imp::Options options;
                options.outliers.enabled = false;
                return static_cast<std::uint64_t>(imp::import_file(path, options, report).size());
            }));
            results.push_back(time_it("prt import_file (+outliers)", repeat, [&] {
                imp::Report report;
                imp::Options options;
                return static_cast<std::uint64_t>(imp::import_file(path, options, report).size());
            }));
            results.push_back(time_it("prt import + pool write", repeat, [&] {
                imp::Report report;
                imp::Options options;
                const auto cloud = imp::import_file(path, options, report);
                prt::pool::PoolWriter writer;
                prt::pre::write_point_sections(cloud, writer);
                writer.add_provenance("prt-bench-import", PRT_VERSION, "{}");
                writer.write(pool_path);
                return static_cast<std::uint64_t>(cloud.size());
            }));
#ifdef PRT_BENCH_PCL
            results.push_back(
                time_it("pcl::PLYReader", repeat, [&] { return prt_bench::read_with_pcl(path.string()); }));
#endif
#ifdef PRT_BENCH_OPENMESH
            results.push_back(time_it("OpenMesh read_mesh", repeat,
                                      [&] { return prt_bench::read_with_openmesh(path.string()); }));
#endif
            std::printf("%-30s %10s %10s %10s\n", "reader", "median_s", "min_s", "points");
            for (const Result& r : results)
                std::printf("%-30s %10.3f %10.3f %10llu\n", r.name.c_str(), r.median, r.min,
                            static_cast<unsigned long long>(r.points));
            fs::remove(pool_path);
            if (temporary) fs::remove(path);
        });
}
