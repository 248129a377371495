// Tests of the out-of-core brick build (bricks_from_points.h, issue 17): built cell by cell from the
// points, the bricks equal byte for byte what the in-core pipeline builds (build_octree ->
// cull_octree -> build_bricks, the code of prt-octree, prt-cull and prt-bricks).
#include "bricks_from_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "point_cloud.h"
#include "prt/error.h"
#include "prt/formats/pool.h"
#include "runtime/tool_run.h"

namespace prt {
namespace {

/// A scan-like model: a noisy ground plane whose density falls off with distance from a scanner,
/// a sphere standing on it, a few unusable points; colours from the position, k-NN-like radii.
struct Scan {
    std::vector<pool::Float3> positions, normals;
    std::vector<float> radii;
    std::vector<pool::Rgba8> colors;
};

Scan scan_model(std::size_t n, std::uint32_t seed) {
    Scan s;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.002);
    for (std::size_t i = 0; i < n; ++i) {
        double p[3], nn[3];
        if (i % 3 != 0) {  // ground: denser near the scanner at the origin
            const double r = 4.0 * std::pow(u(rng), 1.7), a = 6.283185307179586 * u(rng);
            p[0] = r * std::cos(a), p[1] = r * std::sin(a), p[2] = noise(rng);
            nn[0] = noise(rng), nn[1] = noise(rng), nn[2] = 1.0;
        } else {  // sphere of radius 0.8 on the ground
            const double z = 2.0 * u(rng) - 1.0, a = 6.283185307179586 * u(rng), q = std::sqrt(1.0 - z * z);
            nn[0] = q * std::cos(a), nn[1] = q * std::sin(a), nn[2] = z;
            p[0] = 1.5 + 0.8 * nn[0], p[1] = 0.5 + 0.8 * nn[1], p[2] = 0.8 + 0.8 * nn[2];
        }
        const double d = std::sqrt(p[0] * p[0] + p[1] * p[1]);
        s.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
        s.normals.push_back({float(nn[0]), float(nn[1]), float(nn[2])});
        s.radii.push_back(float((0.012 + 0.01 * d) * (0.8 + 0.4 * u(rng))));
        s.colors.push_back(
            {std::uint8_t(128 + 30 * p[0]), std::uint8_t(128 + 30 * p[1]), std::uint8_t(i % 251), 255});
    }
    s.radii[7] = 0.0f;  // skipped by the octree
    s.normals[11] = {0.0f, 0.0f, 0.0f};
    s.positions[13].x = std::nanf("");
    return s;
}

struct Pipeline {
    pre::OctreeParams octree;
    pre::CullParams culling;
    pre::BrickParams bricks;
    bool cull = true;
    Pipeline() {
        octree.max_leaf_splats = 24;
        octree.threads = 2;
        culling.backend = "cpu";
        culling.threads = 2;
        bricks.brick_splats = 700;
        bricks.threads = 2;
    }
};

/// The in-core pipeline: prt-octree, prt-cull, prt-bricks.
pre::BrickedOctree in_core(const Scan& s, const Pipeline& setup, pre::BrickStats* stats) {
    const pre::SplatOctree octree = pre::build_octree(s.positions, s.normals, s.radii, setup.octree);
    pool::SplatOctreeSections sections{octree.info, octree.nodes, octree.leaf_info, octree.splats};
    pre::CulledOctree culled;
    if (setup.cull) {
        culled = pre::cull_octree(sections, setup.culling);
        sections = pool::SplatOctreeSections{culled.info, octree.nodes, culled.leaf_info, culled.splats};
    }
    return pre::build_bricks(sections, s.colors, setup.bricks, stats);
}

pre::PointBrickParams point_params(const Pipeline& setup, std::uint64_t cell_points) {
    pre::PointBrickParams p;
    p.octree = setup.octree;
    p.cull = setup.cull;
    p.culling = setup.culling;
    p.bricks = setup.bricks;
    p.cell_points = cell_points;
    p.threads = 2;
    p.spill_folder = std::filesystem::temp_directory_path();
    return p;
}

pre::PointBricks out_of_core(const Scan& s, const Pipeline& setup, std::uint64_t cell_points,
                             pre::PointBrickStats* stats) {
    return pre::build_bricks_from_points(s.positions, s.normals, s.radii, s.colors,
                                         point_params(setup, cell_points), stats);
}

/// A fresh folder for a staged build, removed at the end of the test.
struct StageFolder {
    std::filesystem::path path;
    explicit StageFolder(const std::string& suffix = "") {
        path = std::filesystem::temp_directory_path() /
               ("prt-cells-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name() + suffix);
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~StageFolder() { std::filesystem::remove_all(path); }
};

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

template <class T>
void expect_same_bytes(const std::vector<T>& a, const std::vector<T>& b, const char* what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    for (std::size_t i = 0; i < a.size(); ++i)
        ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof(T)), 0) << what << " " << i << " of " << a.size();
}

void expect_equal(const pre::BrickedOctree& ref, const pre::PointBricks& got) {
    EXPECT_EQ(std::memcmp(&ref.info, &got.bricks.info, sizeof ref.info), 0) << "brick_info";
    expect_same_bytes(ref.top_nodes, got.bricks.top_nodes, "top node");
    expect_same_bytes(ref.table, got.bricks.table, "brick entry");
    expect_same_bytes(ref.lod, got.bricks.lod, "LOD disc");
    expect_same_bytes(ref.lod_table, got.bricks.lod_table, "LOD prefix entry");
    expect_same_bytes(ref.lod_nodes, got.bricks.lod_nodes, "LOD prefix node");
    expect_same_bytes(ref.lod_discs, got.bricks.lod_discs, "LOD prefix disc");
    ASSERT_EQ(ref.data.size(), got.data_bytes);
    std::vector<std::byte> data;
    got.data([&](const std::byte* p, std::size_t n) { data.insert(data.end(), p, p + n); });
    ASSERT_EQ(data.size(), ref.data.size());
    ASSERT_EQ(std::memcmp(ref.data.data(), data.data(), ref.data.size()), 0) << "brick payloads differ";
}

TEST(BricksFromPoints, CulledCellByCellEqualsTheInCorePipeline) {
    const Scan s = scan_model(30000, 3);
    const Pipeline setup;
    pre::BrickStats ref_stats;
    const pre::BrickedOctree ref = in_core(s, setup, &ref_stats);
    ASSERT_GT(ref.table.size(), 20u);
    pre::PointBrickStats stats;
    const pre::PointBricks got = out_of_core(s, setup, 2500, &stats);
    EXPECT_GE(stats.cells, 10u) << "the partition must cut the model into many cells";
    EXPECT_GE(stats.partition_depth, 2u);
    EXPECT_EQ(stats.points, 30000u - 3u);
    EXPECT_EQ(stats.skipped, 3u);
    EXPECT_LT(stats.culled_splats, stats.stored_splats);
    expect_equal(ref, got);
    EXPECT_EQ(stats.bricks.bricks, ref_stats.bricks);
    EXPECT_EQ(stats.bricks.top_depth, ref_stats.top_depth);
    EXPECT_EQ(stats.bricks.encoded, ref_stats.encoded);
    EXPECT_EQ(stats.bricks.error.splats, ref_stats.error.splats);
    // Cells built by 3 workers at once, and a memory budget too small to keep each point's cell
    // from the count pass for the scatter (which then classifies every point again): the same
    // bytes, the same counts.
    pre::PointBrickParams p = point_params(setup, 2500);
    p.cell_workers = 3;
    p.memory = 64 << 10;
    pre::PointBrickStats concurrent;
    expect_equal(ref,
                 pre::build_bricks_from_points(s.positions, s.normals, s.radii, s.colors, p, &concurrent));
    EXPECT_EQ(concurrent.cells, stats.cells);
    EXPECT_EQ(concurrent.stored_splats, stats.stored_splats);
    EXPECT_EQ(concurrent.culled_splats, stats.culled_splats);
    EXPECT_EQ(concurrent.cell_records, stats.cell_records);
}

TEST(BricksFromPoints, UnculledAndSplitByCentresEqualTheInCorePipeline) {
    const Scan s = scan_model(12000, 5);
    Pipeline setup;
    setup.cull = false;
    expect_equal(in_core(s, setup, nullptr), out_of_core(s, setup, 1500, nullptr));
    setup.octree.split_by_centres = true;
    setup.cull = true;
    expect_equal(in_core(s, setup, nullptr), out_of_core(s, setup, 1500, nullptr));
}

TEST(BricksFromPoints, OneCellWhenTheModelFits) {
    const Scan s = scan_model(5000, 9);
    const Pipeline setup;
    pre::PointBrickStats stats;
    const pre::PointBricks got = out_of_core(s, setup, 0, &stats);
    EXPECT_EQ(stats.cells, 1u);
    EXPECT_EQ(stats.partition_depth, 0u);
    expect_equal(in_core(s, setup, nullptr), got);
}

TEST(BricksFromPoints, EveryPointCountsOnceInTheRootDisc) {
    // The LOD sums count each point once, in the leaf holding its centre: the root disc's centre is
    // the area-weighted mean of the usable points (computed here independently, in double).
    const Scan s = scan_model(8000, 4);
    const Pipeline setup;
    const pre::PointBricks got = out_of_core(s, setup, 1000, nullptr);
    double w = 0, c[3] = {0, 0, 0};
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const pool::Float3 p = s.positions[i], n = s.normals[i];
        if (!(s.radii[i] > 0) || !std::isfinite(p.x) || (n.x == 0 && n.y == 0 && n.z == 0)) continue;
        const double a = 3.141592653589793 * double(s.radii[i]) * s.radii[i];
        w += a;
        c[0] += a * p.x, c[1] += a * p.y, c[2] += a * p.z;
    }
    const pool::LodSplat& root = got.bricks.lod.at(0);
    EXPECT_NEAR(root.position.x, c[0] / w, 1e-5);
    EXPECT_NEAR(root.position.y, c[1] / w, 1e-5);
    EXPECT_NEAR(root.position.z, c[2] / w, 1e-5);
}

TEST(BricksFromPoints, StagedBuildInPartsEqualsTheInCorePipeline) {
    // Issue 21: one model's cells built by separate builders (here separate calls, each reading only
    // the plan and its cells' records, as a cluster's processes do), in any order, then merged.
    const Scan s = scan_model(30000, 3);
    const Pipeline setup;
    pre::BrickStats ref_stats;
    const pre::BrickedOctree ref = in_core(s, setup, &ref_stats);
    const pre::PointBrickParams p = point_params(setup, 2500);
    const StageFolder folder;
    pre::PointBrickStats plan_stats;
    const std::uint32_t cells =
        pre::plan_brick_cells(s.positions, s.normals, s.radii, s.colors, p, folder.path, &plan_stats);
    ASSERT_GE(cells, 10u);
    EXPECT_EQ(pre::planned_brick_cells(folder.path, p), cells);
    const std::uint32_t a = cells / 3, b = 2 * cells / 3;
    pre::PointBrickParams other_threads = p;
    other_threads.threads = 1;  // threads, workers, memory and the spill folder may differ between stages
    other_threads.cell_workers = 2;
    pre::build_brick_cells(folder.path, p, b, cells);
    pre::build_brick_cells(folder.path, other_threads, 0, a);
    pre::build_brick_cells(folder.path, p, a, b);
    pre::PointBrickStats stats;
    const pre::PointBricks got = pre::merge_brick_cells(folder.path, p, &stats);
    expect_equal(ref, got);
    pre::PointBrickStats whole;
    out_of_core(s, setup, 2500, &whole);
    EXPECT_EQ(stats.cells, whole.cells);
    EXPECT_EQ(stats.points, whole.points);
    EXPECT_EQ(stats.stored_splats, whole.stored_splats);
    EXPECT_EQ(stats.culled_splats, whole.culled_splats);
    EXPECT_EQ(stats.bricks.bricks, ref_stats.bricks);
    EXPECT_EQ(stats.bricks.error.splats, ref_stats.error.splats);
    // A new plan in the same folder drops the old parts: merging now names the missing cells.
    pre::plan_brick_cells(s.positions, s.normals, s.radii, s.colors, p, folder.path);
    EXPECT_NE(error_of([&] {
                  pre::merge_brick_cells(folder.path, p);
              }).find("cells 0:" + std::to_string(cells) + " are not built"),
              std::string::npos);
}

TEST(BricksFromPoints, StagedReplanLeavesTheOldRecordsToTheirReaders) {
    // A cell builder may still be reading the old plan's records when a new plan starts in the same
    // folder: the new records must be a new file, not the old one truncated and rewritten.
    const Scan first = scan_model(12000, 5), second = scan_model(9000, 7);
    const Pipeline setup;
    const pre::PointBrickParams p = point_params(setup, 1500);
    const StageFolder folder;
    pre::plan_brick_cells(first.positions, first.normals, first.radii, first.colors, p, folder.path);
    const std::filesystem::path records = folder.path / "records.bin";
    // a cell builder of the first plan that finishes after the second plan started: its part, and
    // the first plan's plan.bin read with the second plan's records, are refused
    pre::build_brick_cells(folder.path, p, 0, 1);
    const StageFolder old_files("-old");
    std::filesystem::copy_file(folder.path / "cells-0-1.bin", old_files.path / "cells-0-1.bin");
    std::filesystem::copy_file(folder.path / "plan.bin", old_files.path / "plan.bin");
    const auto read_all = [](std::istream& in) {
        in.clear();
        in.seekg(0);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    std::ifstream reader(records, std::ios::binary);  // the running builder's view
    const std::string old_records = read_all(reader);
    ASSERT_GT(old_records.size(), 0u);
    const std::uint32_t cells =
        pre::plan_brick_cells(second.positions, second.normals, second.radii, second.colors, p, folder.path);
    EXPECT_EQ(read_all(reader), old_records);
    std::ifstream now(records, std::ios::binary);
    EXPECT_NE(read_all(now), old_records);
    // no temporary file left behind, and the new plan builds
    for (const auto& entry : std::filesystem::directory_iterator(folder.path))
        EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
    pre::build_brick_cells(folder.path, p, 1, cells);
    std::filesystem::copy_file(old_files.path / "cells-0-1.bin", folder.path / "cells-0-1.bin");
    std::string e = error_of([&] { pre::merge_brick_cells(folder.path, p); });
    EXPECT_NE(e.find("cells-0-1.bin: built from another plan"), std::string::npos) << e;
    std::filesystem::rename(folder.path / "plan.bin", old_files.path / "plan-2.bin");
    std::filesystem::copy_file(old_files.path / "plan.bin", folder.path / "plan.bin");
    e = error_of([&] { pre::build_brick_cells(folder.path, p, 0, 1); });
    EXPECT_NE(e.find("records.bin: "), std::string::npos) << e;
    std::filesystem::copy_file(old_files.path / "plan-2.bin", folder.path / "plan.bin",
                               std::filesystem::copy_options::overwrite_existing);
    pre::build_brick_cells(folder.path, p, 0, 1);  // over the stale part
    expect_equal(in_core(second, setup, nullptr), pre::merge_brick_cells(folder.path, p));
}

TEST(BricksFromPoints, StagedBuildNeedsOutputOnlyToMerge) {
    // Issue 17's wart: prt-bricks --stage plan and cells write only into --cells-folder, so they run
    // without -o, and a -o given there is ignored with one note (not even checked: a cell worker need
    // not see OUTPUT's folder); the merge and the whole build still refuse to run without -o.
    const StageFolder dir, cells("-cells");
    const auto file = [&](const std::string& name) { return (dir.path / name).string(); };
    const Scan s = scan_model(12000, 5);
    pre::PointCloud cloud;
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const pool::Float3 p = s.positions[i];
        if (!std::isfinite(p.x)) continue;  // a pool holds finite positions only
        cloud.positions.push_back({p.x, p.y, p.z});
        cloud.normals.push_back(s.normals[i]);
        cloud.colors.push_back(s.colors[i]);
        cloud.radii.push_back(s.radii[i]);
    }
    {
        pool::PoolWriter w;
        pre::write_point_sections(cloud, w);
        w.write(file("radii.pool"));
    }
    const std::string staged = " --cells-folder " + cells.path.string();
    const auto run = [&](const std::string& args) {
        return test::run_tool(
            "prt-bricks",
            file("radii.pool") + " " + args + " --backend cpu -j 2 --cell-points 1500 --brick-splats 700",
            dir.path);
    };
    const std::string required = "prt-bricks: error: --output is required (see --help)\n";
    test::ToolRun r = run("--stage plan" + staged + " -q --stats-json " + file("plan.json"));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    const std::uint32_t n =
        nlohmann::json::parse(test::slurp(file("plan.json")))["cells"].get<std::uint32_t>();
    ASSERT_GE(n, 4u);
    const std::string half = std::to_string(n / 2), all = std::to_string(n);
    r = run("--stage cells --cells 0:" + half + staged + " -q");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    const std::string elsewhere = file("no/such/folder/out.pool");
    r = run("--stage cells --cells " + half + ":" + all + staged + " -o " + elsewhere);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("prt-bricks: -o " + elsewhere +
                         " ignored: --stage cells writes its part into --cells-folder\n"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.path / "no"));
    EXPECT_TRUE(std::filesystem::exists(cells.path / ("cells-" + half + "-" + all + ".bin")));
    // -o given to the plan: ignored too (the plan does not write spill files beside it either)
    r = run("--stage plan" + staged + " -o " + elsewhere);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("prt-bricks: -o " + elsewhere + " ignored: --stage plan writes"), std::string::npos)
        << r.err;
    // a cell worker need not see INPUT either (it reads only --cells-folder); the whole build does
    const auto run_without_input = [&](const std::string& args) {
        return test::run_tool(
            "prt-bricks",
            file("nowhere.pool") + " " + args + " --backend cpu -j 2 --cell-points 1500 --brick-splats 700",
            dir.path);
    };
    r = run_without_input("--stage cells --cells 0:" + all + staged + " -q");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(run_without_input("-q -o " + file("x.pool")).err,
              "prt-bricks: error: " + file("nowhere.pool") + ": no such file\n");
    // the merge and the whole build write OUTPUT: without -o, the same usage error as every tool's
    r = run("--stage merge" + staged);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, required);
    r = run("-q");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, required);
    r = run("--stage merge" + staged + " -q -o " + file("staged.pool"));
    ASSERT_EQ(r.code, 0) << r.err;
    r = run("-q -o " + file("whole.pool"));
    ASSERT_EQ(r.code, 0) << r.err;
    const pool::PoolFile a = pool::PoolFile::open(file("staged.pool")),
                         b = pool::PoolFile::open(file("whole.pool"));
    for (const pool::SectionType t : {pool::SectionType::brick_info, pool::SectionType::brick_table,
                                      pool::SectionType::brick_data, pool::SectionType::lod_discs}) {
        ASSERT_TRUE(a.has(t) && b.has(t)) << int(t);
        const auto x = a.bytes(*a.find(t)), y = b.bytes(*b.find(t));
        EXPECT_TRUE(x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size()) == 0) << int(t);
    }
    // A part whose payload was damaged after it was built: the merge reads the payloads as it writes
    // the pool, so the write fails with one line naming the part, and the pool written before stays.
    const std::string before = test::slurp(file("staged.pool"));
    const std::filesystem::path part = cells.path / ("cells-0-" + all + ".bin");  // the last cells stage's
    {
        // a byte half way through the payloads (the footer's first word: where they end)
        std::fstream f(part, std::ios::in | std::ios::out | std::ios::binary);
        ASSERT_TRUE(f.is_open()) << part;
        std::uint64_t end = 0;
        f.seekg(-32, std::ios::end);
        f.read(reinterpret_cast<char*>(&end), sizeof end);
        ASSERT_GT(end, 0u);
        char c = 0;
        f.seekg(std::streamoff(end / 2));
        f.read(&c, 1);
        c = char(c ^ 0x5a);
        f.seekp(std::streamoff(end / 2));
        f.write(&c, 1);
    }
    r = run("--stage merge" + staged + " -q -o " + file("staged.pool"));
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(r.err, "prt-bricks: error: " + part.string() +
                         ": checksum mismatch: corrupt, truncated or not written by this prt-bricks\n");
    EXPECT_TRUE(test::slurp(file("staged.pool")) == before);
    for (const auto& entry : std::filesystem::directory_iterator(dir.path))
        EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
}

TEST(BricksFromPoints, StagedBuildRefusesMissingCorruptOverlappingAndForeignParts) {
    const Scan s = scan_model(12000, 5);
    const Pipeline setup;
    const pre::PointBrickParams p = point_params(setup, 1500);
    const StageFolder folder;
    EXPECT_NE(error_of([&] { pre::build_brick_cells(folder.path, p, 0, 1); }).find("no plan.bin"),
              std::string::npos);
    const std::uint32_t cells =
        pre::plan_brick_cells(s.positions, s.normals, s.radii, s.colors, p, folder.path);
    ASSERT_GE(cells, 4u);
    pre::build_brick_cells(folder.path, p, 0, 2);
    pre::build_brick_cells(folder.path, p, 3, cells);
    // cell 2 missing: named with the command that builds it
    std::string e = error_of([&] { pre::merge_brick_cells(folder.path, p); });
    EXPECT_NE(e.find("cells 2:3 are not built (prt-bricks --stage cells --cells 2:3)"), std::string::npos)
        << e;
    // a range outside the plan
    e = error_of([&] { pre::build_brick_cells(folder.path, p, 1, cells + 1); });
    EXPECT_NE(e.find("outside the plan's 0:" + std::to_string(cells)), std::string::npos) << e;
    // other options than the plan's
    pre::PointBrickParams other = p;
    other.bricks.brick_splats += 1;
    e = error_of([&] { pre::build_brick_cells(folder.path, other, 2, 3); });
    EXPECT_NE(e.find("planned with other options"), std::string::npos) << e;
    // overlapping parts
    pre::build_brick_cells(folder.path, p, 1, 3);
    e = error_of([&] { pre::merge_brick_cells(folder.path, p); });
    EXPECT_NE(e.find("is also in"), std::string::npos) << e;
    std::filesystem::remove(folder.path / "cells-0-2.bin");
    pre::build_brick_cells(folder.path, p, 0, 1);
    const pre::PointBricks merged = pre::merge_brick_cells(folder.path, p);  // 0:1, 1:3, 3:N
    expect_equal(in_core(s, setup, nullptr), merged);
    // a flipped byte in a part's payload, then in the plan: refused, naming the file
    const std::filesystem::path part = folder.path / "cells-1-3.bin";
    {
        std::fstream f(part, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(100);
        char c = 0;
        f.read(&c, 1);
        f.seekp(100);
        c = char(c ^ 0x5a);
        f.write(&c, 1);
    }
    // (the payloads are read, and their checksums checked, as the pool is written: PointBricks::data)
    e = error_of([&] { pre::merge_brick_cells(folder.path, p).data([](const std::byte*, std::size_t) {}); });
    EXPECT_NE(e.find(part.string() + ": checksum mismatch"), std::string::npos) << e;
    std::filesystem::resize_file(folder.path / "plan.bin", 40);
    e = error_of([&] { pre::merge_brick_cells(folder.path, p); });
    EXPECT_NE(e.find("plan.bin: checksum mismatch"), std::string::npos) << e;
}

TEST(BricksFromPoints, BadInputIsRefused) {
    Scan s = scan_model(100, 1);
    s.radii.pop_back();
    const Pipeline setup;
    EXPECT_THROW(out_of_core(s, setup, 0, nullptr), Error);
    Scan none = scan_model(100, 1);
    for (float& r : none.radii) r = 0.0f;
    try {
        out_of_core(none, setup, 0, nullptr);
        FAIL() << "no usable point";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no point has a finite positive radius"), std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace prt
