// Out-of-core PCA normals (issue 17): pca_normals_tiled against the in-core pca_normals over the
// graph of outliers_and_graph (itself checked against analytic normals in normals_test.cpp), bit
// for bit, with tiles and memory forced small, on a scan-like cloud far from the origin with uneven
// density, exact duplicates (ties) and degenerate (collinear) neighbourhoods.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "neighbours.h"

namespace {

using prt::pool::Float3;

std::vector<std::array<double, 3>> scan_like_points() {
    std::vector<std::array<double, 3>> p;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double ox = 4.5e5, oy = 5.2e6, oz = 120.0;  // georeferenced-like offsets
    // a wavy ground patch, denser near a "scanner" at the origin corner
    for (int i = 0; i < 2500; ++i) {
        const double r = 20.0 * u(rng) * u(rng), t = 1.5707963 * u(rng);
        const double x = r * std::cos(t), y = r * std::sin(t);
        p.push_back({ox + x, oy + y, oz + 0.2 * std::sin(x) * std::cos(0.5 * y)});
    }
    // a sphere (closed surface) and a straight line of points (collinear neighbourhoods: NaN)
    for (int i = 0; i < 1200; ++i) {
        const double z = 2 * u(rng) - 1, t = 6.2831853 * u(rng), s = std::sqrt(1 - z * z);
        p.push_back({ox + 8 + s * std::cos(t), oy + 8 + s * std::sin(t), oz + 2 + z});
    }
    for (int i = 0; i < 40; ++i) p.push_back({ox - 5 - 0.01 * i, oy - 5, oz});
    for (int i = 0; i < 30; ++i) p.push_back(p[std::size_t(i) * 41]);  // exact duplicates
    std::shuffle(p.begin(), p.end(), rng);
    return p;
}

TEST(TiledNormals, EqualTheInCorePcaNormalsBitForBit) {
    using namespace prt::pre::import;
    const std::uint32_t k = 24;
    prt::pre::PointCloud cloud;
    cloud.positions = scan_like_points();
    const auto positions = cloud.positions;
    OutlierParams params;
    params.enabled = false;
    KnnGraph graph;
    OutlierReport report;
    outliers_and_graph(cloud, params, k, &graph, report, true);
    ASSERT_EQ(cloud.size(), positions.size());
    const std::vector<Float3> want = pca_normals(cloud.positions, graph, k, true);
    std::size_t nan = 0;
    for (const Float3& n : want) nan += !std::isfinite(n.x);
    EXPECT_GT(nan, 0u);  // the line
    for (const std::uint64_t tile : {100u, 800u})
        for (const std::uint64_t memory : {std::uint64_t(1) << 30, std::uint64_t(60000)}) {
            SCOPED_TRACE("tile " + std::to_string(tile) + ", memory " + std::to_string(memory));
            prt::pre::TiledKnnParams tiling;
            tiling.tile_points = tile;
            tiling.memory = memory;
            tiling.threads = 2;
            tiling.spill_folder = std::filesystem::temp_directory_path();
            std::vector<Float3> got(positions.size());
            prt::pre::TiledKnnStats stats;
            pca_normals_tiled(positions, k, tiling, got, &stats);
            EXPECT_GT(stats.tiles, 1u);
            EXPECT_GT(stats.halo_queries, 0u);
            for (std::size_t i = 0; i < want.size(); ++i)
                ASSERT_EQ(std::memcmp(&got[i], &want[i], sizeof(Float3)), 0)
                    << "point " << i << ": " << got[i].x << " " << got[i].y << " " << got[i].z << " vs "
                    << want[i].x << " " << want[i].y << " " << want[i].z;
        }
}

}  // namespace
