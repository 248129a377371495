// The splat octree's GPU builder (runtime/cuda/src/octree_build.cu) against the CPU builder
// (preprocess/splat/octree_build.cpp), byte for byte: node words, leaf ranges, splats (replicas and
// their order in each leaf), the header's counts and the statistics, for whole trees and for cells
// of an out-of-core build, on a room and a sphere whose radii vary (so the cell-size rule's mean
// is near the edge in some nodes and its list-order sum decides), for every builder option; and
// cells built and culled in one pass on the GPU (build_culled_cell) against the CPU's two steps.
// Label gpu: skips with the reason where no CUDA device is usable.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cull_build.h"
#include "octree_build.h"
#include "prt/error.h"
#include "splat_test_data.h"
#include "synth.h"

namespace {

using namespace prt;

bool usable(std::string& why) {
    try {
        pre::resolve_octree_backend("cuda");
        return true;
    } catch (const Error& e) {
        why = e.what();
        return false;
    }
}

/// A model whose radii vary by a factor up to 2 about the k-NN spacing of its density.
test::SplatSet room(std::uint64_t n) {
    synth::SynthOptions o;
    o.shape.kind = synth::ShapeKind::room;
    o.count = n;
    synth::SynthResult r = synth::synthesize(o);
    double area = 0;
    for (const synth::PartRange& p : r.parts) area += p.area;
    const double base = 1.1 * std::sqrt(9.0 * area / (3.14159265358979323846 * double(n)));
    test::SplatSet s;
    for (const auto& p : r.cloud.positions) s.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
    s.normals = r.cloud.normals;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> f(0.7, 1.4);
    for (std::size_t i = 0; i < s.positions.size(); ++i) s.radii.push_back(float(base * f(rng)));
    return s;
}

test::SplatSet sphere(std::uint64_t n) {
    test::SplatSet s = test::sphere_points(n, 11);
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> f(0.5, 2.0);
    const double base = 1.1 * std::sqrt(9.0 * 4.0 / double(n));
    for (std::size_t i = 0; i < s.positions.size(); ++i) s.radii.push_back(float(base * f(rng)));
    s.radii[3] = 0.0f;  // skipped by both
    return s;
}

void expect_same(const pre::SplatOctree& a, const pre::SplatOctree& b, const pre::OctreeStats& sa,
                 const pre::OctreeStats& sb) {
    EXPECT_EQ(0, std::memcmp(&a.info, &b.info, sizeof a.info));
    ASSERT_EQ(a.nodes.size(), b.nodes.size());
    EXPECT_EQ(a.nodes, b.nodes);
    EXPECT_EQ(a.leaf_info, b.leaf_info);
    ASSERT_EQ(a.splats.size(), b.splats.size());
    EXPECT_EQ(0, std::memcmp(a.splats.data(), b.splats.data(), a.splats.size() * sizeof(pool::Splat)));
    EXPECT_EQ(sa.nodes, sb.nodes);
    EXPECT_EQ(sa.depth, sb.depth);
    EXPECT_EQ(sa.filled_leaves, sb.filled_leaves);
    EXPECT_EQ(sa.empty_leaves, sb.empty_leaves);
    EXPECT_EQ(sa.unique_splats, sb.unique_splats);
    EXPECT_EQ(sa.stored_splats, sb.stored_splats);
    EXPECT_EQ(sa.skipped_splats, sb.skipped_splats);
    EXPECT_EQ(sa.max_leaf_count, sb.max_leaf_count);
    EXPECT_EQ(sa.bytes, sb.bytes);
}

struct Variant {
    const char* name;
    pre::OctreeParams params;
};

std::vector<Variant> variants() {
    std::vector<Variant> v;
    v.push_back({"defaults", {}});
    pre::OctreeParams p;
    p.max_leaf_splats = 8;
    v.push_back({"X = 8", p});
    p = {};
    p.max_depth = 5;
    v.push_back({"max depth 5", p});
    p = {};
    p.min_cell_ratio = 0;
    v.push_back({"no cell-size rule", p});
    p = {};
    p.min_cell_ratio = 2.0f;
    v.push_back({"cell-size rule 2", p});
    p = {};
    p.split_by_centres = true;
    v.push_back({"split by centres", p});
    p = {};
    p.replicate = false;
    v.push_back({"not replicated", p});
    return v;
}

TEST(OctreeGpu, WholeTreesEqualTheCpuBuilders) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    for (const auto& [model_name, model] :
         {std::pair{"room", room(60000)}, std::pair{"sphere", sphere(30000)}}) {
        for (Variant v : variants()) {
            SCOPED_TRACE(std::string(model_name) + ", " + v.name);
            v.params.threads = 2;
            pre::OctreeStats sc, sg;
            const pre::SplatOctree cpu =
                pre::build_octree(model.positions, model.normals, model.radii, v.params, &sc);
            v.params.backend = "cuda";
            const pre::SplatOctree gpu =
                pre::build_octree(model.positions, model.normals, model.radii, v.params, &sg);
            EXPECT_GT(cpu.info.filled_leaves, 10u);
            expect_same(cpu, gpu, sc, sg);
        }
    }
}

/// The points of `model` whose disk reaches node `cell` as the out-of-core build decides it: level
/// by level from the root, through child_overlap_mask (build_octree_cell's contract).
test::SplatSet cell_points(const test::SplatSet& model, const pool::OctreeInfo& root, pre::NodeCell cell,
                           bool replicate) {
    test::SplatSet out;
    for (std::size_t i = 0; i < model.positions.size(); ++i) {
        pre::BuildSplat s;
        if (!pre::prepare_build_splat(model.positions[i], model.normals[i], model.radii[i], s)) continue;
        bool in = true;
        for (std::uint32_t l = 0; l < cell.level && in; ++l) {
            const std::uint32_t shift = cell.level - l;
            const pre::NodeCell node{l,
                                     {cell.cell[0] >> shift, cell.cell[1] >> shift, cell.cell[2] >> shift}};
            const unsigned child = ((cell.cell[0] >> (shift - 1)) & 1u) |
                                   (((cell.cell[1] >> (shift - 1)) & 1u) << 1) |
                                   (((cell.cell[2] >> (shift - 1)) & 1u) << 2);
            in = (pre::child_overlap_mask(s, pre::child_boxes(root, node), replicate) >> child) & 1u;
        }
        if (!in) continue;
        out.positions.push_back(model.positions[i]);
        out.normals.push_back(model.normals[i]);
        out.radii.push_back(model.radii[i]);
    }
    return out;
}

TEST(OctreeGpu, CellsOfAnOutOfCoreBuildEqualTheCpuBuilders) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    const test::SplatSet model = room(80000);
    pre::RootBounds bounds;
    for (std::size_t i = 0; i < model.positions.size(); ++i)
        bounds.add(model.positions[i], model.normals[i], model.radii[i]);
    const pool::OctreeInfo root = bounds.root();
    int cells = 0;
    for (const pre::NodeCell cell : {pre::NodeCell{1, {0, 0, 0}}, pre::NodeCell{2, {0, 1, 3}},
                                     pre::NodeCell{2, {3, 3, 3}}, pre::NodeCell{3, {0, 2, 5}}}) {
        for (Variant v : {variants()[0], variants()[1], variants()[5]}) {
            const test::SplatSet pts = cell_points(model, root, cell, v.params.replicate);
            if (pts.positions.size() < 200) continue;
            SCOPED_TRACE("cell " + std::to_string(cell.level) + " (" + std::to_string(cell.cell[0]) + "," +
                         std::to_string(cell.cell[1]) + "," + std::to_string(cell.cell[2]) + "), " + v.name +
                         ", " + std::to_string(pts.positions.size()) + " points");
            v.params.threads = 2;
            pre::OctreeStats sc, sg;
            const pre::SplatOctree cpu =
                pre::build_octree_cell(pts.positions, pts.normals, pts.radii, root, cell, v.params, &sc);
            v.params.backend = "cuda";
            const pre::SplatOctree gpu =
                pre::build_octree_cell(pts.positions, pts.normals, pts.radii, root, cell, v.params, &sg);
            expect_same(cpu, gpu, sc, sg);
            ++cells;
        }
    }
    EXPECT_GE(cells, 6);
}

/// `s` with points the builder skips slipped in at the front, the middle and the back (a zero
/// normal, a zero, an infinite and a NaN radius, a NaN position), each beside a copy of a usable
/// point's position so that it would share its Morton key: the records made on the device must skip
/// them and keep the usable points' input order exactly as the CPU does.
test::SplatSet with_unusable_points(test::SplatSet s) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const std::size_t n = s.positions.size();
    for (const std::size_t at : {std::size_t(0), n / 2, n}) {
        const pool::Float3 p = s.positions[at < n ? at : n - 1];
        const pool::Float3 nz = s.normals[at < n ? at : n - 1];
        const float r = s.radii[at < n ? at : n - 1];
        const pool::Float3 ps[5] = {p, p, p, p, {nan, p.y, p.z}};
        const pool::Float3 ns[5] = {{0, 0, 0}, nz, nz, nz, nz};
        const float rs[5] = {r, 0.0f, inf, nan, r};
        s.positions.insert(s.positions.begin() + std::ptrdiff_t(at), ps, ps + 5);
        s.normals.insert(s.normals.begin() + std::ptrdiff_t(at), ns, ns + 5);
        s.radii.insert(s.radii.begin() + std::ptrdiff_t(at), rs, rs + 5);
    }
    return s;
}

/// The out-of-core build's cells built, culled and compacted on the GPU (cull_build.h,
/// build_culled_cell over build_cull_octree_cuda, the build records made on the device) against
/// build_octree_cell then cull_octree on the CPU: the same header, nodes, culled leaf ranges and
/// kept splats (whose point indices say the records' order), for both probe policies that keep
/// replicas one by one, with points the builder skips among the cell's.
TEST(OctreeGpu, CellsBuiltAndCulledOnTheDeviceEqualTheCpuSteps) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    const test::SplatSet model = room(80000);
    pre::RootBounds bounds;
    for (std::size_t i = 0; i < model.positions.size(); ++i)
        bounds.add(model.positions[i], model.normals[i], model.radii[i]);
    const pool::OctreeInfo root = bounds.root();
    int cells = 0;
    for (const pre::NodeCell cell : {pre::NodeCell{1, {0, 0, 0}}, pre::NodeCell{2, {0, 1, 3}},
                                     pre::NodeCell{2, {3, 3, 3}}, pre::NodeCell{3, {0, 2, 5}}}) {
        for (Variant v : {variants()[0], variants()[1], variants()[5]}) {
            const test::SplatSet pts = with_unusable_points(cell_points(model, root, cell, true));
            if (pts.positions.size() < 200) continue;
            for (const pre::CullPolicy policy : {pre::CullPolicy::greedy, pre::CullPolicy::votes}) {
                SCOPED_TRACE("cell " + std::to_string(cell.level) + " (" + std::to_string(cell.cell[0]) +
                             "," + std::to_string(cell.cell[1]) + "," + std::to_string(cell.cell[2]) + "), " +
                             v.name + (policy == pre::CullPolicy::votes ? ", votes" : ", greedy") + ", " +
                             std::to_string(pts.positions.size()) + " points");
                v.params.threads = 2;
                v.params.backend = "cpu";
                pre::CullParams cp;
                cp.policy = policy;
                cp.threads = 2;
                cp.backend = "cpu";
                const pre::SplatOctree built =
                    pre::build_octree_cell(pts.positions, pts.normals, pts.radii, root, cell, v.params);
                const pre::CulledOctree cpu = pre::cull_octree(
                    pool::SplatOctreeSections{built.info, built.nodes, built.leaf_info, built.splats}, cp,
                    nullptr, pre::OctreePart{cell});
                const pre::CulledCell steps =
                    pre::build_culled_cell(pts.positions, pts.normals, pts.radii, root, cell, v.params, cp);
                EXPECT_FALSE(steps.on_device);
                v.params.backend = "cuda";
                cp.backend = "cuda";
                const pre::CulledCell gpu =
                    pre::build_culled_cell(pts.positions, pts.normals, pts.radii, root, cell, v.params, cp);
                EXPECT_TRUE(gpu.on_device);
                pre::OctreeStats built_stats;
                pre::build_octree_cell(pts.positions, pts.normals, pts.radii, root, cell, v.params,
                                       &built_stats);
                EXPECT_EQ(15u, built_stats.skipped_splats);
                EXPECT_EQ(pts.positions.size() - 15, built.info.unique_splats);
                EXPECT_EQ(built.splats.size(), gpu.stored);
                EXPECT_EQ(built.splats.size(), steps.stored);
                EXPECT_LT(cpu.splats.size(), built.splats.size());  // culling removed replicas
                for (const pre::CulledCell* c : {&steps, &gpu}) {
                    EXPECT_EQ(0, std::memcmp(&cpu.info, &c->octree.info, sizeof cpu.info));
                    EXPECT_EQ(built.nodes, c->octree.nodes);
                    EXPECT_EQ(cpu.leaf_info, c->octree.leaf_info);
                    ASSERT_EQ(cpu.splats.size(), c->octree.splats.size());
                    EXPECT_EQ(0, std::memcmp(cpu.splats.data(), c->octree.splats.data(),
                                             cpu.splats.size() * sizeof(pool::Splat)));
                }
                ++cells;
            }
        }
    }
    EXPECT_GE(cells, 12);
}

}  // namespace
