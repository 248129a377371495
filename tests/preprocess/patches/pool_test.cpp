// The patch sections: pool round trip, the BVH's structure and boxes, its depth guard, orientation
// of a closed model, and validate_patches' one-line errors on pools broken in each way it checks.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <random>

#include "patch_build.h"
#include "patch_pool.h"
#include "patch_test_util.h"
#include "prt/runtime/surface_pools.h"

namespace {

using namespace prt::patch_test;
using prt::pool::SectionType;
namespace fs = std::filesystem;

std::vector<Net> grid_nets(int n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::vector<Net> nets;
    for (int i = 0; i < n; ++i) {
        Net net = random_net(rng, 1.0);
        for (auto& p : net.p) p = {p.x + 1.3 * (i % 7), p.y + 1.1 * (i / 7), p.z + 0.2 * (i % 3)};
        nets.push_back(net);
    }
    return nets;
}

TEST(PatchPool, RoundTripThroughAFile) {
    const std::vector<Net> nets = grid_nets(40, 15);
    prt::patches::BuildOptions o;
    o.depth = 5;
    o.orient = false;
    const auto model = prt::patches::build_patch_model(nets, o);
    prt::pool::PoolWriter w;
    prt::patches::write_patch_sections(model, w);
    w.add_provenance("pool_test", "0", "{}");
    const fs::path path =
        fs::temp_directory_path() / ("prt_patch_pool_" + std::to_string(::getpid()) + ".pool");
    w.write(path);
    {
        const auto pool = prt::pool::PoolFile::open(path);
        const auto view = prt::rt::load_patch_view(pool);
        EXPECT_EQ(view.patch_count, 40u);
        EXPECT_EQ(view.subpatch_depth, 5u);
        EXPECT_EQ(view.subpatch_nodes, 63u);
        EXPECT_EQ(view.bvh_node_count, 79u);
        EXPECT_EQ(pool.model_info().point_count, 0u);
        EXPECT_FALSE(pool.has(SectionType::positions));
        ASSERT_EQ(std::memcmp(view.nets, model.nets.data(), model.nets.size() * sizeof(Net)), 0);
        ASSERT_EQ(std::memcmp(view.bvh, model.bvh.data(), model.bvh.size() * sizeof(prt::pool::PatchBvhNode)),
                  0);
        ASSERT_EQ(
            std::memcmp(view.nodes, model.nodes.data(), model.nodes.size() * sizeof(prt::pool::SubpatchNode)),
            0);
        // local frame: world = local + origin, exactly as read
        const auto& mi = pool.model_info();
        for (std::size_t p = 0; p < nets.size(); ++p)
            for (int k = 0; k < 16; ++k) {
                EXPECT_NEAR(view.nets[p].p[k].x + mi.origin[0], nets[p].p[k].x, 1e-15);
                EXPECT_NEAR(view.nets[p].p[k].z + mi.origin[2], nets[p].p[k].z, 1e-15);
            }
        EXPECT_NE(pool.provenance_json().find("pool_test"), std::string::npos);
        EXPECT_TRUE(prt::patches::has_patches(pool));
    }
    fs::remove(path);
}

/// Independent check of the depth-first layout: returns the subtree end of node i, checks boxes.
std::uint32_t check_subtree(const prt::core::PatchView& v, std::uint32_t i, std::vector<int>& seen,
                            std::uint32_t depth, std::uint32_t& deepest) {
    deepest = std::max(deepest, depth);
    const auto& node = v.bvh[i];
    if (node.patch >= 0) {
        ++seen[node.patch];
        // the leaf box holds every control point of its patch
        for (const auto& p : v.nets[node.patch].p) {
            EXPECT_LE(node.lo[0], p.x);
            EXPECT_GE(node.hi[0], p.x);
            EXPECT_LE(node.lo[2], p.z);
            EXPECT_GE(node.hi[2], p.z);
        }
        EXPECT_EQ(node.skip, i + 1);
        return i + 1;
    }
    const std::uint32_t left_end = check_subtree(v, i + 1, seen, depth + 1, deepest);
    const std::uint32_t right_end = check_subtree(v, left_end, seen, depth + 1, deepest);
    for (std::uint32_t c : {i + 1, left_end})
        for (int a = 0; a < 3; ++a) {
            EXPECT_LE(node.lo[a], v.bvh[c].lo[a]);
            EXPECT_GE(node.hi[a], v.bvh[c].hi[a]);
        }
    EXPECT_EQ(node.skip, right_end);
    return right_end;
}

TEST(PatchPool, BvhIsDepthFirstWithSkipsAndContainingBoxes) {
    const BuiltPool bp = build_pool(grid_nets(100, 16), 3);
    std::vector<int> seen(100, 0);
    std::uint32_t deepest = 0;
    EXPECT_EQ(check_subtree(bp.view, 0, seen, 0, deepest), bp.view.bvh_node_count);
    for (int s : seen) EXPECT_EQ(s, 1);
    // SAH on a 7 x 15 grid of patches: close to balanced (log2(100) ~ 6.6)
    EXPECT_LE(deepest, 12u);
    const auto& info = bp.file.array<prt::pool::PatchInfo>(SectionType::patch_info)[0];
    EXPECT_EQ(info.bvh_depth, deepest);
}

TEST(PatchPool, DepthGuardBoundsDegenerateInputs) {
    // Boxes at exponentially growing positions: a greedy SAH split peels one box per level.
    std::vector<prt::patches::Box> boxes;
    for (int i = 0; i < 200; ++i) {
        prt::patches::Box b;
        const double x = std::ldexp(1.0, 2 * i);
        b.lo[0] = x, b.hi[0] = x * 1.01, b.lo[1] = 0, b.hi[1] = 1, b.lo[2] = 0, b.hi[2] = 1;
        boxes.push_back(b);
    }
    prt::patches::BvhStats st;
    const auto nodes = prt::patches::build_patch_bvh(boxes, 16, 0.0, &st);
    EXPECT_EQ(nodes.size(), 399u);
    EXPECT_LE(st.depth, prt::pool::k_max_patch_bvh_depth);
    EXPECT_GT(st.median_splits, 0u);  // the guard did step in
    // and identical boxes (coincident centroids) split by the median
    std::vector<prt::patches::Box> same(33, boxes[0]);
    const auto n2 = prt::patches::build_patch_bvh(same, 16, 0.0, &st);
    EXPECT_EQ(n2.size(), 65u);
    EXPECT_EQ(st.depth, 6u);
}

/// A closed cube of 6 planar patches, each face given with a random u/v order.
std::vector<Net> cube_nets(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::vector<Net> nets;
    for (int axis = 0; axis < 3; ++axis)
        for (double side : {0.0, 1.0}) {
            V3 o{0, 0, 0}, a{0, 0, 0}, b{0, 0, 0};
            o[axis] = side;
            a[(axis + 1) % 3] = 1;
            b[(axis + 2) % 3] = 1;
            Net n = planar_net(o, a, b);
            if (rng() & 1) n = prt::patches::transpose_net(n);
            nets.push_back(n);
        }
    return nets;
}

TEST(PatchPool, OrientationOfAClosedCubePointsOutwards) {
    for (std::uint64_t seed = 0; seed < 8; ++seed) {
        std::vector<Net> nets = cube_nets(seed);
        const auto st = prt::patches::orient_patches(nets);
        EXPECT_EQ(st.components, 1u);
        EXPECT_EQ(st.shared_edges, 12u);
        EXPECT_EQ(st.boundary_edges, 0u);
        EXPECT_EQ(st.conflicts, 0u);
        for (const Net& n : nets) {
            const MatrixEval e = matrix_eval(n, 0.5, 0.5);
            const V3 normal = cross3(e.qu, e.qv);
            EXPECT_GT(dot3(normal, sub(e.q, {0.5, 0.5, 0.5})), 0.0) << "seed " << seed;
        }
    }
}

TEST(PatchPool, AFlatGroupKeepsTheFilesOrientation) {
    // A floor has no inside: its signed volume about the model's centre (which lies in its plane) is
    // rounding noise. It oriented the patch at random by its sign (a floor at z = -1.4 turned to
    // face down, at z = -1.3 up); now the file's orientation stays, in either direction.
    for (double z : {-2.0, -1.4, -1.39, -1.3, -0.7, 0.0, 0.3}) {
        for (bool transposed : {false, true}) {
            std::vector<Net> nets = {planar_net({-1, -1, z}, {2, 0, 0}, {0, 2, 0})};
            if (transposed) nets[0] = prt::patches::transpose_net(nets[0]);
            const Net before = nets[0];
            const auto st = prt::patches::orient_patches(nets);
            EXPECT_EQ(st.flipped, 0u) << "z " << z;
            EXPECT_EQ(st.flat_components, 1u) << "z " << z;
            EXPECT_EQ(std::memcmp(&before, &nets[0], sizeof(Net)), 0) << "z " << z;
        }
    }
}

// ---- validate_patches errors: pools with valid checksums but broken contents --------------------

struct Parts {
    prt::pool::ModelInfo model;
    prt::pool::PatchInfo info;
    std::vector<Net> nets;
    std::vector<prt::pool::PatchBvhNode> bvh;
    std::vector<prt::pool::SubpatchNode> nodes;
};

Parts good_parts() {
    prt::patches::BuildOptions o;
    o.depth = 2;
    const auto m = prt::patches::build_patch_model(grid_nets(5, 17), o);
    return {m.model_info, m.patch_info, m.nets, m.bvh, m.nodes};
}

std::string load_error(const Parts& p, bool skip_bvh = false) {
    prt::pool::PoolWriter w;
    w.add_array(SectionType::model_info, std::vector<prt::pool::ModelInfo>{p.model});
    w.add_array(SectionType::patch_info, std::vector<prt::pool::PatchInfo>{p.info});
    w.add_array(SectionType::patch_control_points, p.nets);
    if (!skip_bvh) w.add_array(SectionType::patch_bvh, p.bvh);
    w.add_array(SectionType::patch_subpatch_boxes, p.nodes);
    try {
        const auto pool = prt::pool::PoolFile::from_bytes(w.serialize(), "bad.pool");
        prt::patches::validate_patches(pool);
    } catch (const prt::Error& e) {
        return e.what();
    }
    return "";
}

TEST(PatchPool, PoolWithoutPatches) {
    prt::pool::PoolWriter w;
    w.add_array(SectionType::model_info, std::vector<prt::pool::ModelInfo>{good_parts().model});
    const auto pool = prt::pool::PoolFile::from_bytes(w.serialize(), "points.pool");
    EXPECT_FALSE(prt::patches::has_patches(pool));
    try {
        prt::patches::validate_patches(pool);
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_STREQ(e.what(), "points.pool: no patch sections (run prt-patches)");
    }
}

TEST(PatchPool, BrokenSectionsGiveOneLineErrors) {
    EXPECT_EQ(load_error(good_parts()), "");
    struct Case {
        const char* expect;
        std::function<void(Parts&)> breaks;
        bool skip_bvh = false;
    };
    const std::vector<Case> cases = {
        {"section patch_info: the patches need all of", [](Parts&) {}, true},
        {"section patch_control_points: 4 control nets but patch_info says 5",
         [](Parts& p) { p.nets.pop_back(); }},
        {"section patch_info: 9 BVH nodes for 4 patches", [](Parts& p) { p.info.patch_count = 4; }},
        {"section patch_subpatch_boxes: 34 boxes", [](Parts& p) { p.nodes.pop_back(); }},
        {"section patch_info: 8 subpatch nodes per patch, depth 2 needs 7",
         [](Parts& p) { p.info.subpatch_nodes = 8; }},
        {"section patch_info: subpatch depth 11 exceeds 10", [](Parts& p) { p.info.subpatch_depth = 11; }},
        {"section patch_control_points: patch 3: control point not finite",
         [](Parts& p) { p.nets[3].p[7].y = NAN; }},
        {"section patch_subpatch_boxes: box 9: not finite, inverted",
         [](Parts& p) { p.nodes[9].lo[1] = p.nodes[9].hi[1] + 1; }},
        {"section patch_bvh: node 0: skip 3, expected 9", [](Parts& p) { p.bvh[0].skip = 3; }},
        {"section patch_bvh: node 0: box not finite", [](Parts& p) { p.bvh[0].hi[2] = INFINITY; }},
        {"out of range",
         [](Parts& p) {
             for (auto& n : p.bvh)
                 if (n.patch >= 0) {
                     n.patch = 5;
                     break;
                 }
         }},
        {"in two leaves",
         [](Parts& p) {
             int first = -1;
             for (auto& n : p.bvh)
                 if (n.patch >= 0) {
                     if (first < 0)
                         first = n.patch;
                     else {
                         n.patch = first;
                         break;
                     }
                 }
         }},
        {"is invalid", [](Parts& p) { p.bvh[0].patch = -7; }},
        {"right child", [](Parts& p) { p.bvh[1].skip = 1; }},
        {"but patch_info says", [](Parts& p) { p.info.bvh_depth += 1; }},
    };
    for (const Case& c : cases) {
        Parts p = good_parts();
        c.breaks(p);
        const std::string err = load_error(p, c.skip_bvh);
        EXPECT_NE(err.find(c.expect), std::string::npos)
            << "expected \"" << c.expect << "\", got \"" << err << "\"";
        EXPECT_EQ(err.rfind("bad.pool: ", 0), 0u) << err;  // names the file first
        EXPECT_EQ(err.find('\n'), std::string::npos) << err;
    }
}

}  // namespace
