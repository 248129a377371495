// splat-bench-gen: writes a synthetic point model for scripts/bench-splat.sh (used when bin/prt-synth
// is not built): N points uniformly at random on a unit sphere with radial normals, optionally
// sorted along a Morton curve (scan files are spatially coherent; random order is the worst case).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "morton.h"
#include "point_cloud.h"
#include "prt/tool.h"

int main(int argc, char** argv) {
    std::string output;
    std::uint64_t count = 1000000, seed = 1;
    bool sorted = false;
    return prt::tool::run(
        argc, argv, "splat-bench-gen",
        "Benchmark model for the splat tools: N random points on a unit sphere.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("output", output, "Output pool file")->required();
            app.add_option("-n,--points", count, "Number of points")->check(CLI::Range(1ull, 1ull << 31));
            app.add_option("--seed", seed, "Random seed");
            app.add_flag("--sorted", sorted, "Store the points in Morton order instead of random order");
        },
        [&](const prt::tool::CommonOptions& common) {
            std::mt19937_64 rng(seed);
            std::normal_distribution<double> g(0.0, 1.0);
            prt::pre::PointCloud cloud;
            cloud.positions.reserve(count);
            cloud.normals.reserve(count);
            while (cloud.positions.size() < count) {
                double v[3] = {g(rng), g(rng), g(rng)};
                const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                if (len < 1e-9) continue;
                cloud.positions.push_back({v[0] / len, v[1] / len, v[2] / len});
                cloud.normals.push_back({float(v[0] / len), float(v[1] / len), float(v[2] / len)});
            }
            if (sorted) {
                std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(count);
                for (std::uint32_t i = 0; i < count; ++i) {
                    std::uint32_t q[3];
                    for (int a = 0; a < 3; ++a)
                        q[a] = std::uint32_t((cloud.positions[i][a] + 1.0) * 0.5 * 2097151.0);
                    keys[i] = {prt::pre::morton3(q[0], q[1], q[2]), i};
                }
                std::sort(keys.begin(), keys.end());
                prt::pre::PointCloud s;
                for (const auto& [k, i] : keys) {
                    s.positions.push_back(cloud.positions[i]);
                    s.normals.push_back(cloud.normals[i]);
                }
                cloud = std::move(s);
            }
            cloud.flags = prt::pool::k_model_synthetic;
            prt::pool::PoolWriter writer;
            prt::pre::write_point_sections(cloud, writer);
            writer.add_provenance("splat-bench-gen", PRT_VERSION,
                                  "{\"shape\":\"sphere\",\"points\":" + std::to_string(count) +
                                      ",\"seed\":" + std::to_string(seed) +
                                      ",\"sorted\":" + (sorted ? "true" : "false") + "}");
            writer.write(output);
            prt::tool::note(common.quiet, "splat-bench-gen: wrote %llu points to %s",
                            static_cast<unsigned long long>(count), output.c_str());
        });
}
