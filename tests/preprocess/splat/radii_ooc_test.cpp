// Out-of-core k-NN radii (issue 17): the tiled search (tiled_knn.h) and compute_radii_tiled against
// the in-core kd-tree over all points (itself checked against brute force in radii_test.cpp), on
// clouds of uneven density with exact ties, with tiles and memory forced small; the streamed median
// against a sort; prt-radii --tile-points / --memory end to end against the in-core run.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "kd_tree.h"
#include "point_cloud.h"
#include "prt/formats/pool.h"
#include "prt/tool_util.h"
#include "radii.h"
#include "splat_test_data.h"
#include "tiled_knn.h"

namespace {

namespace fs = std::filesystem;
using prt::pool::Float3;

/// Uneven density: a dense blob, a sparse sphere, a lattice (many exactly equal distances: ties),
/// exact duplicates, a line of isolated points far away and a lone outlier.
std::vector<Float3> uneven_points() {
    std::vector<Float3> p = prt::test::sphere_points(1500, 41, 3.0).positions;
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<float> u(-0.05f, 0.05f);
    for (int i = 0; i < 1500; ++i) p.push_back({1 + u(rng), 0.5f + u(rng), u(rng)});
    for (int x = 0; x < 10; ++x)
        for (int y = 0; y < 10; ++y)
            for (int z = 0; z < 6; ++z)
                p.push_back({-2.0f + 0.125f * x, -1.0f + 0.125f * y, 0.5f + 0.125f * z});
    for (int i = 0; i < 40; ++i) p.push_back(p[std::size_t(i) * 37]);
    for (int i = 0; i < 12; ++i) p.push_back({0.25f, 0.75f, -0.5f});  // 12 coincident: radius 0
    for (int i = 0; i < 8; ++i) p.push_back({10.0f + 3.0f * i, -7.0f, 2.0f});
    p.push_back({-40, 40, -40});
    std::shuffle(p.begin(), p.end(), rng);  // input order unrelated to space
    return p;
}

/// The in-core neighbours and squared distances of every point (KdTree::for_each over all).
void in_core_knn(const std::vector<Float3>& p, std::uint32_t k, std::vector<std::uint32_t>& nb,
                 std::vector<float>& d2) {
    const prt::pre::KdTree<float> tree(
        p.size(), [&](std::size_t i, float c[3]) { c[0] = p[i].x, c[1] = p[i].y, c[2] = p[i].z; });
    nb.assign(p.size() * k, 0);
    d2.assign(p.size() * k, 0);
    tree.for_each(k, 2, [&](std::uint32_t i, const std::uint32_t* index, const float* dist2, std::uint32_t) {
        std::copy_n(index, k, nb.data() + std::size_t(i) * k);
        std::copy_n(dist2, k, d2.data() + std::size_t(i) * k);
    });
}

struct TiledCase {
    std::uint64_t tile_points;
    std::uint64_t memory;
};

TEST(TiledKnn, NeighboursEqualTheInCoreSearchWithTies) {
    const std::vector<Float3> p = uneven_points();
    for (const std::uint32_t k : {1u, 9u, 16u}) {
        std::vector<std::uint32_t> want_nb;
        std::vector<float> want_d2;
        in_core_knn(p, k, want_nb, want_d2);
        // tiles of 40 to 2000 points; memory from generous to a few dozen points (groups split,
        // points scanned alone)
        for (const TiledCase c : {TiledCase{2000, 1u << 30}, TiledCase{300, 1u << 30},
                                  TiledCase{40, 1u << 30}, TiledCase{300, 40000}, TiledCase{100, 2000}}) {
            SCOPED_TRACE("k = " + std::to_string(k) + ", tile points " + std::to_string(c.tile_points) +
                         ", memory " + std::to_string(c.memory));
            prt::pre::TiledKnnParams params;
            params.k = k;
            params.threads = 2;
            params.tile_points = c.tile_points;
            params.memory = c.memory;
            params.spill_folder = fs::temp_directory_path();
            std::vector<std::uint32_t> got_nb(p.size() * k, ~0u);
            std::vector<float> got_d2(p.size() * k, -1.0f);
            std::vector<int> seen(p.size(), 0);
            prt::pre::TiledKnnStats stats;
            std::uint64_t last_progress = 0;
            prt::pre::tiled_knn(
                p, params,
                [&](const prt::pre::KnnBatch& b) {
                    ASSERT_TRUE(std::is_sorted(b.global.begin(), b.global.end()));
                    for (std::size_t q = 0; q < b.queries.size(); ++q) {
                        const std::uint32_t g = b.global[b.queries[q]];
                        ++seen[g];
                        for (std::uint32_t j = 0; j < k; ++j) {
                            got_nb[std::size_t(g) * k + j] = b.global[b.neighbours[q * k + j]];
                            got_d2[std::size_t(g) * k + j] = b.distance2[q * k + j];
                        }
                    }
                },
                [&](std::uint64_t done) { last_progress = done; }, &stats);
            EXPECT_EQ(last_progress, p.size());
            EXPECT_GT(stats.tiles, 1u);
            for (std::size_t i = 0; i < p.size(); ++i) ASSERT_EQ(seen[i], 1) << "point " << i;
            for (std::size_t i = 0; i < p.size() * k; ++i) {
                ASSERT_EQ(got_nb[i], want_nb[i]) << "point " << i / k << " neighbour " << i % k;
                ASSERT_EQ(std::memcmp(&got_d2[i], &want_d2[i], sizeof(float)), 0) << "point " << i / k;
            }
            if (c.memory < 100000) {
                EXPECT_GT(stats.scanned + stats.halo_groups, stats.tiles / 2);
            }
        }
    }
}

TEST(TiledKnn, LargeTilesOrderedInParallelGiveTheInCoreNeighbours) {
    // Tiles of more than 2^16 records, so each tile's Morton order, sort and blocks are computed by
    // several workers (tiled_knn.cpp order_tile): the neighbours still equal the in-core search's.
    std::vector<Float3> p = prt::test::sphere_points(300000, 7, 2.0).positions;
    std::mt19937_64 rng(3);
    std::shuffle(p.begin(), p.end(), rng);
    const std::uint32_t k = 9;
    std::vector<std::uint32_t> want_nb;
    std::vector<float> want_d2;
    in_core_knn(p, k, want_nb, want_d2);
    prt::pre::TiledKnnParams params;
    params.k = k;
    params.threads = 4;
    params.tile_points = 140000;
    params.spill_folder = fs::temp_directory_path();
    std::vector<std::uint32_t> got_nb(p.size() * k, ~0u);
    prt::pre::TiledKnnStats stats;
    prt::pre::tiled_knn(
        p, params,
        [&](const prt::pre::KnnBatch& b) {
            for (std::size_t q = 0; q < b.queries.size(); ++q)
                for (std::uint32_t j = 0; j < k; ++j)
                    got_nb[std::size_t(b.global[b.queries[q]]) * k + j] = b.global[b.neighbours[q * k + j]];
        },
        {}, &stats);
    EXPECT_GE(stats.tiles, 2u);
    EXPECT_GT(stats.halo_queries, 0u);
    for (std::size_t i = 0; i < got_nb.size(); ++i)
        ASSERT_EQ(got_nb[i], want_nb[i]) << "point " << i / k << " neighbour " << i % k;
}

TEST(TiledKnn, HalosThatDoNotFitAsOneSetAreSearchedByFace) {
    // A jittered plane cut into tiles whose memory holds a tile and a little more, not a tile with
    // its halo all round: round 2 gathers each face's failing points as a thin slab with its halo
    // (tiled_knn.cpp round2), so most of them are searched in groups. Before, the failing points'
    // box spanned the whole tile, did not fit, and every one of them was scanned alone.
    std::vector<Float3> p;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
    for (int x = 0; x < 450; ++x)
        for (int y = 0; y < 450; ++y) p.push_back({x + jitter(rng), y + jitter(rng), 0.1f * jitter(rng)});
    std::shuffle(p.begin(), p.end(), rng);
    const std::uint32_t k = 9;
    std::vector<std::uint32_t> want_nb;
    std::vector<float> want_d2;
    in_core_knn(p, k, want_nb, want_d2);
    prt::pre::TiledKnnParams params;
    params.k = k;
    params.threads = 2;
    params.tile_points = 20000;
    params.memory = 24000 * prt::pre::tiled_knn_bytes_per_point(k);
    params.spill_folder = fs::temp_directory_path();
    std::vector<std::uint32_t> got_nb(p.size() * k, ~0u);
    prt::pre::TiledKnnStats stats;
    prt::pre::tiled_knn(
        p, params,
        [&](const prt::pre::KnnBatch& b) {
            for (std::size_t q = 0; q < b.queries.size(); ++q)
                for (std::uint32_t j = 0; j < k; ++j)
                    got_nb[std::size_t(b.global[b.queries[q]]) * k + j] = b.global[b.neighbours[q * k + j]];
        },
        {}, &stats);
    EXPECT_GE(stats.tiles, 8u);
    EXPECT_GT(stats.halo_queries, stats.tiles * 100);
    // runs of a few points are scanned by design (tiled_knn.cpp k_scan_run); the rest in groups
    EXPECT_LT(stats.scanned * 4, stats.halo_queries) << stats.scanned << " scanned";
    EXPECT_GT(stats.halo_groups, stats.tiles);
    EXPECT_LE(stats.max_gathered, 24000u);
    for (std::size_t i = 0; i < got_nb.size(); ++i)
        ASSERT_EQ(got_nb[i], want_nb[i]) << "point " << i / k << " neighbour " << i % k;
}

TEST(TiledKnn, BadInputIsRefused) {
    prt::pre::TiledKnnParams params;
    params.k = 4;
    params.spill_folder = fs::temp_directory_path();
    std::vector<Float3> p(4, Float3{0, 0, 0});
    EXPECT_THROW(prt::pre::tiled_knn(p, params, [](const prt::pre::KnnBatch&) {}), prt::Error);
    p.resize(50, Float3{1, 2, 3});
    p[17].y = std::numeric_limits<float>::quiet_NaN();
    try {
        prt::pre::tiled_knn(p, params, [](const prt::pre::KnnBatch&) {});
        FAIL() << "no error";
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("point 17"), std::string::npos) << e.what();
    }
}

TEST(TiledRadii, EqualTheInCoreRadiiAndStatistics) {
    const std::vector<Float3> p = uneven_points();
    for (const char* scope : {"local", "global"})
        for (const float factor : {0.0f, 1.5f, 3.0f})
            for (const std::uint64_t tile : {60u, 700u}) {
                SCOPED_TRACE(std::string(scope) + ", factor " + std::to_string(factor) + ", tile " +
                             std::to_string(tile));
                prt::pre::RadiiParams params;
                params.k = 9;
                params.clamp_factor = factor;
                params.scope = prt::pre::parse_clamp_scope(scope);
                params.threads = 2;
                prt::pre::RadiiStats want_stats, got_stats;
                const std::vector<float> want = prt::pre::compute_radii(p, params, &want_stats);
                prt::pre::TiledKnnParams tiling;
                tiling.tile_points = tile;
                tiling.memory = 100000;
                tiling.spill_folder = fs::temp_directory_path();
                const prt::pre::SpillFile got = prt::pre::compute_radii_tiled(p, params, tiling, &got_stats);
                ASSERT_EQ(got.size(), want.size() * sizeof(float));
                const auto r = got.as<const float>();
                for (std::size_t i = 0; i < want.size(); ++i)
                    ASSERT_EQ(std::memcmp(&r[i], &want[i], sizeof(float)), 0)
                        << "point " << i << ": " << r[i] << " vs " << want[i];
                EXPECT_EQ(got_stats.points, want_stats.points);
                EXPECT_EQ(got_stats.clamped, want_stats.clamped);
                EXPECT_EQ(got_stats.zero, want_stats.zero);
                EXPECT_EQ(got_stats.raw_median, want_stats.raw_median);
                EXPECT_EQ(got_stats.clamp_limit, want_stats.clamp_limit);
                EXPECT_EQ(got_stats.min, want_stats.min);
                EXPECT_EQ(got_stats.median, want_stats.median);
                EXPECT_EQ(got_stats.mean, want_stats.mean);
                EXPECT_EQ(got_stats.max, want_stats.max);
                if (factor > 0) {
                    EXPECT_GT(want_stats.clamped, 0u);  // the outliers are clamped
                }
                EXPECT_GT(want_stats.zero, 0u);  // the 12 coincident points
            }
}

TEST(TiledRadii, StreamedMedianEqualsTheSortedMiddle) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 10.0f);
    for (const std::size_t n : {1u, 2u, 7u, 1000u, 1001u}) {
        std::vector<float> v(n);
        for (float& x : v) x = std::floor(u(rng) * 4) / 4;  // many equal values
        if (n > 3) v[1] = -2.5f, v[2] = 0.0f;
        std::vector<float> s = v;
        std::sort(s.begin(), s.end());
        const double want = n % 2 ? s[n / 2] : 0.5 * (double(s[n / 2 - 1]) + double(s[n / 2]));
        EXPECT_EQ(prt::pre::median_streaming(v), want) << n;
    }
}

TEST(ByteSize, ParsesSuffixesAndRefusesTheRest) {
    using prt::tool::parse_byte_size;
    EXPECT_EQ(parse_byte_size("1000"), 1000u);
    EXPECT_EQ(parse_byte_size("512M"), 512ull << 20);
    EXPECT_EQ(parse_byte_size("4g"), 4ull << 30);
    EXPECT_EQ(parse_byte_size("1.5G"), 3ull << 29);
    EXPECT_EQ(parse_byte_size("2GiB"), 2ull << 30);
    EXPECT_EQ(parse_byte_size("64KB"), 64ull << 10);
    EXPECT_EQ(parse_byte_size("1T"), 1ull << 40);
    for (const char* bad : {"", "G", "-1G", "0", "12Q", "1.5 G", "nan", "inf", "1e30G", "4GG"})
        EXPECT_THROW(parse_byte_size(bad, "--memory"), prt::Error) << bad;
}

class RadiiTool : public ::testing::Test {
protected:
    void SetUp() override {
        m_dir = fs::temp_directory_path() / ("prt_radii_ooc_" + std::to_string(::getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override { fs::remove_all(m_dir); }
    int run(const std::string& args, const std::string& out = "/dev/null") {
        const std::string cmd = (fs::path(PRT_BIN_DIR) / "prt-radii").string() + " " + args + " >" + out +
                                " 2>" + (m_dir / "err.txt").string();
        const int status = std::system(cmd.c_str());
        std::ifstream in(m_dir / "err.txt");
        std::stringstream ss;
        ss << in.rdbuf();
        m_stderr = ss.str();
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    std::string path(const std::string& name) const { return (m_dir / name).string(); }
    fs::path m_dir;
    std::string m_stderr;
};

TEST_F(RadiiTool, OutOfCoreEqualsInCore) {
    prt::pre::PointCloud cloud;
    for (const Float3& q : uneven_points()) cloud.positions.push_back({1e3 + q.x, q.y, q.z});
    prt::pool::PoolWriter writer;
    prt::pre::write_point_sections(cloud, writer);
    writer.add_provenance("radii_ooc_test", "0", "{}");
    writer.write(path("in.pool"));
    ASSERT_EQ(run(path("in.pool") + " -o " + path("core.pool") + " --memory 1G"), 0) << m_stderr;
    EXPECT_EQ(m_stderr.find("out of core"), std::string::npos) << m_stderr;
    for (const std::string opts :
         {"--tile-points 150", "--memory 40K", "--memory 40K --clamp-scope global"}) {
        SCOPED_TRACE(opts);
        // --backend cpu: the tiled search is the CPU's (a GPU path, where there is one, would hold
        // all of this model's radii within 40K and never tile)
        ASSERT_EQ(run(path("in.pool") + " -o " + path("tiled.pool") + " --backend cpu --spill-folder " +
                      m_dir.string() + " " + opts),
                  0)
            << m_stderr;
        EXPECT_NE(m_stderr.find("out of core"), std::string::npos) << m_stderr;
        if (opts.find("global") != std::string::npos) {
            ASSERT_EQ(run(path("in.pool") + " -o " + path("core.pool") + " --clamp-scope global"), 0)
                << m_stderr;
        }
        const auto a = prt::pool::PoolFile::open(path("core.pool"));
        const auto b = prt::pool::PoolFile::open(path("tiled.pool"));
        const auto ra = a.array<float>(prt::pool::SectionType::radii);
        const auto rb = b.array<float>(prt::pool::SectionType::radii);
        ASSERT_EQ(ra.size(), cloud.size());
        ASSERT_EQ(rb.size(), ra.size());
        EXPECT_EQ(std::memcmp(ra.data(), rb.data(), ra.size_bytes()), 0);
    }
    // documented in --help (with the default), the testing option hidden
    ASSERT_EQ(run("--help", path("help.txt")), 0);
    std::ifstream help_file(path("help.txt"));
    std::stringstream help;
    help << help_file.rdbuf();
    for (const char* opt : {"--memory", "--spill-folder", "half the physical memory"})
        EXPECT_NE(help.str().find(opt), std::string::npos) << opt;
    EXPECT_EQ(help.str().find("--tile-points"), std::string::npos);
    // the spill files are gone; a bad size is a usage error
    for (const auto& e : fs::directory_iterator(m_dir))
        EXPECT_EQ(e.path().filename().string().find("prt-spill"), std::string::npos) << e.path();
    EXPECT_EQ(run(path("in.pool") + " -o " + path("x.pool") + " --memory 12Q"), 2) << m_stderr;
    EXPECT_NE(m_stderr.find("--memory"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("x.pool")));
}

}  // namespace
