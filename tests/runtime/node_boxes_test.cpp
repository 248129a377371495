// Node boxes (core::NodeBox, rt::build_node_boxes, core::descend_boxed): the splat walks step over
// an internal node whose disks the ray misses altogether. The tests: over replicated trees and trees
// without replicas (each disk in its centre's leaf only, as culling leaves the most), tiny and
// huge models, rays from inside, outside and far away, axis-parallel and short ones, the closest and any
// hit are bit-identical with and without the boxes, and the walks visit fewer leaves; the boxes
// hold every hittable disk (checked against the splats, in double); a node pool laid out otherwise
// gets no boxes; the mask marks the children whose box a line through their cell meets with a
// chance under k_node_box_test_below.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include "prt/core/splat.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/error.h"
#include "prt/runtime/leaf_bounds.h"
#include "prt/runtime/render_scene.h"
#include "test_scene.h"

namespace prt::test {
namespace {

struct BoxCase {
    const char* name;
    bool replicate;
    double scale;  // model size
};

void PrintTo(const BoxCase& c, std::ostream* os) {
    *os << c.name;
}

/// A room (inward walls, one missing) with a ball in it, scaled by `scale` about `centre`.
std::vector<TestPoint> room_with_ball(double scale, const D3& centre) {
    std::vector<TestPoint> pts = room_points(-1.0, 1.0, 40, 5, {200, 180, 160, 255});
    const auto ball = sphere_points({0.2, -0.4, -0.3}, 0.35, 6000, false, {90, 140, 250, 255});
    pts.insert(pts.end(), ball.begin(), ball.end());
    for (TestPoint& p : pts) {
        p.position = d3_add(centre, d3_mul(p.position, scale));
        p.radius *= scale;
    }
    return pts;
}

core::Vec3 random_dir(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        core::Vec3 v{g(rng), g(rng), g(rng)};
        // One ray in eight runs parallel to one or two axes (d components exactly 0).
        const unsigned flat = rng() % 16;
        if (flat == 0) v.x = 0.0f;
        if (flat == 1) v.y = v.z = 0.0f;
        if (core::length2(v) > 1e-6f) return core::normalize(v);
    }
}

/// Walks `rays` random rays through views `a` and `b` of one model of size `scale` and checks that
/// their closest hits (bit for bit) and any hits agree: origins inside the room, on its walls' side,
/// outside up to 4 sizes away, and 60 sizes away aimed into the room (the node boxes' margin grows
/// with the origin's distance); short and unbounded, inside and outside rays, deep blending or not.
/// Returns the closest hits and the occluded rays found.
std::pair<std::size_t, std::size_t> same_hits(const core::OctreeView& a, const core::OctreeView& b,
                                              float scale, unsigned seed, core::WalkStats& a_stats,
                                              core::WalkStats& b_stats) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), u01(0.0f, 1.0f);
    const float s = scale;
    std::size_t hits = 0, occluded = 0;
    for (int i = 0; i < 6000; ++i) {
        const float reach = i % 3 == 0 ? 0.9f : i % 3 == 1 ? 1.2f : 4.0f;
        core::Vec3 o{u(rng) * reach * s, u(rng) * reach * s, u(rng) * reach * s};
        core::Vec3 d = random_dir(rng) * (i % 5 == 0 ? 3.0f : 1.0f);
        if (i % 5 == 4) {
            o = random_dir(rng) * (60.0f * s);
            d = core::normalize(core::Vec3{u(rng) * s, u(rng) * s, u(rng) * s} - o);
        }
        const float t_max = i % 4 == 0 ? u01(rng) * 2.0f * s : core::k_inf;
        const bool inside = i % 7 == 0;
        core::BlendOptions blend;
        blend.deep = i % 2 == 0;
        blend.window = i % 2 == 0 ? 2.0f : 1.0f;
        core::SplatSample ha{}, hb{};
        const bool fa = core::closest_hit_splats(a, nullptr, o, d, inside, t_max, blend, 4096, ha, a_stats);
        const bool fb = core::closest_hit_splats(b, nullptr, o, d, inside, t_max, blend, 4096, hb, b_stats);
        EXPECT_EQ(fa, fb) << "ray " << i;
        if (fa && fb) {
            ++hits;
            EXPECT_EQ(0, std::memcmp(&ha, &hb, sizeof ha)) << "ray " << i << ": t " << ha.t << " vs " << hb.t;
        }
        const bool oa = core::any_hit_splats(a, o, d, inside, t_max, 4096, a_stats);
        const bool ob = core::any_hit_splats(b, o, d, inside, t_max, 4096, b_stats);
        EXPECT_EQ(oa, ob) << "ray " << i;
        occluded += oa;
    }
    return {hits, occluded};
}

class NodeBoxes : public ::testing::TestWithParam<BoxCase> {};

TEST_P(NodeBoxes, HitsAreBitIdenticalAndFewerLeavesAreVisited) {
    const BoxCase& c = GetParam();
    const TestModel m = make_model(room_with_ball(c.scale, {0, 0, 0}), {0, 0, 0}, 24, 10, c.replicate);
    core::OctreeView plain = m.octree.view();
    const rt::NodeBoxes nb = rt::build_node_boxes(plain, 2);
    ASSERT_FALSE(nb.boxes.empty());
    ASSERT_EQ(nb.mask.size(), nb.boxes.size());
    // Every internal child tested (mask all ones), and the mask as built: both exact.
    const std::vector<std::uint8_t> all(nb.mask.size(), 0xff);
    for (const std::uint8_t* mask : {all.data(), nb.mask.data()}) {
        core::OctreeView boxed = plain;
        boxed.node_boxes = nb.boxes.data();
        boxed.node_box_mask = mask;

        core::WalkStats a_stats, b_stats;
        const auto [hits, occluded] =
            same_hits(plain, boxed, static_cast<float>(c.scale), 11, a_stats, b_stats);
        EXPECT_GT(hits, 1000u);
        EXPECT_GT(occluded, 1000u);
        EXPECT_EQ(a_stats.truncated, 0u);
        EXPECT_EQ(b_stats.truncated, 0u);
        EXPECT_LT(b_stats.leaves, a_stats.leaves * 9 / 10) << "the boxes spared under 10 % of the leaves";
        std::printf("%s, %s: leaves %u -> %u, splat tests %u -> %u\n", c.name,
                    mask == all.data() ? "every child tested" : "the mask's children", a_stats.leaves,
                    b_stats.leaves, a_stats.splat_tests, b_stats.splat_tests);
    }
}

INSTANTIATE_TEST_SUITE_P(Cases, NodeBoxes,
                         ::testing::Values(BoxCase{"replicated", true, 1.0},
                                           BoxCase{"one_leaf_per_disk", false, 1.0},
                                           BoxCase{"tiny", false, 1e-3}, BoxCase{"huge", true, 1e5}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(NodeBoxes, EveryBoxHoldsTheDisksBelowItsNode) {
    // Each internal node's box against the disks of its leaves, recomputed here in double.
    const TestModel m = make_model(room_with_ball(1.0, {0, 0, 0}), {0, 0, 0}, 24, 10, true);
    const core::OctreeView v = m.octree.view();
    const rt::NodeBoxes nb = rt::build_node_boxes(v, 1);
    const std::vector<core::NodeBox>& boxes = nb.boxes;
    ASSERT_FALSE(boxes.empty());
    std::size_t checked = 0;
    auto disks_below = [&](auto&& self, std::uint32_t slot, double lo[3], double hi[3]) -> void {
        const std::uint32_t node = v.nodes[slot];
        if (core::node_is_internal(node)) {
            for (std::uint32_t c = 0; c < 8; ++c) self(self, core::node_addr(node) + c, lo, hi);
            return;
        }
        std::uint32_t b, e;
        core::leaf_splats(v, node, b, e);
        for (std::uint32_t i = b; i < e; ++i) {
            const pool::Splat& s = v.splats[i];
            const double n[3] = {s.normal.x, s.normal.y, s.normal.z};
            const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            const double p[3] = {s.position.x, s.position.y, s.position.z};
            const double root[3] = {v.root_min.x, v.root_min.y, v.root_min.z};
            for (int a = 0; a < 3; ++a) {
                const double h = s.radius * std::sqrt(std::max(0.0, 1.0 - (n[a] / len) * (n[a] / len)));
                lo[a] = std::min(lo[a], (p[a] - h - root[a]) / v.root_size);
                hi[a] = std::max(hi[a], (p[a] + h - root[a]) / v.root_size);
            }
        }
    };
    // Cells from the root down, for the mask: child c of a node is marked when a line through its
    // cell meets its disks' box with a chance under rt::k_node_box_test_below (surface areas).
    std::vector<std::array<double, 4>> cell(v.node_count, {0.0, 0.0, 0.0, 1.0});  // corner, size
    std::size_t marked = 0, unmarked = 0;
    std::vector<std::uint32_t> parent_of(v.node_count, 0);
    for (std::uint32_t p = 0; p < v.node_count; ++p)
        if (core::node_is_internal(v.nodes[p]))
            for (std::uint32_t c = 0; c < 8; ++c) parent_of[core::node_addr(v.nodes[p]) + c] = p;
    for (std::uint32_t i = 0; i < v.node_count; ++i) {
        if (!core::node_is_internal(v.nodes[i])) continue;
        double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
        disks_below(disks_below, i, lo, hi);
        const std::uint32_t addr = core::node_addr(v.nodes[i]);
        for (std::uint32_t c = 0; c < 8; ++c) {
            const double h = cell[i][3] / 2;
            cell[addr + c] = {cell[i][0] + h * (c & 1), cell[i][1] + h * ((c >> 1) & 1),
                              cell[i][2] + h * ((c >> 2) & 1), h};
        }
        if (i != 0) {  // this node's bit in its parent's mask
            const std::uint32_t parent = parent_of[i], child = i - core::node_addr(v.nodes[parent]);
            double e[3];
            for (int a = 0; a < 3; ++a)
                e[a] = std::max(0.0, std::min(cell[i][a] + cell[i][3], hi[a]) - std::max(cell[i][a], lo[a]));
            const double chance = (e[0] * e[1] + e[1] * e[2] + e[0] * e[2]) / (3.0 * cell[i][3] * cell[i][3]);
            const bool bit = (nb.mask[(core::node_addr(v.nodes[parent]) - 1u) / 8u] >> child) & 1u;
            if (std::fabs(chance - rt::k_node_box_test_below) > 1e-3)
                EXPECT_EQ(bit, chance < rt::k_node_box_test_below) << "node " << i << ": chance " << chance;
            (bit ? marked : unmarked) += 1;
        }
        const core::NodeBox& b = boxes[(core::node_addr(v.nodes[i]) - 1u) / 8u];
        if (lo[0] > hi[0]) {
            EXPECT_GT(b.lo[0], b.hi[0]) << "node " << i << " has no disk: an empty box";
            continue;
        }
        for (int a = 0; a < 3; ++a) {
            EXPECT_LE(b.lo[a], lo[a]) << "node " << i << " axis " << a;
            EXPECT_GE(b.hi[a], hi[a]) << "node " << i << " axis " << a;
            // tight: within a float rounding of the disks' own extent
            EXPECT_NEAR(b.lo[a], lo[a], 1e-6 * (1.0 + std::fabs(lo[a])));
            EXPECT_NEAR(b.hi[a], hi[a], 1e-6 * (1.0 + std::fabs(hi[a])));
        }
        ++checked;
    }
    EXPECT_GT(checked, 100u);
    EXPECT_GT(marked, 50u);   // the walls' nodes (a slab: about 1/3)
    EXPECT_GT(unmarked, 5u);  // the room's corners and the ball
}

TEST(NodeBoxes, ANodePoolLaidOutOtherwiseGetsNone) {
    // An internal node whose children block lies before it (not the breadth-first layout of
    // prt-octree): no boxes, and the walk then descends as before.
    std::vector<std::uint32_t> nodes(17, core::k_empty_leaf_node);
    nodes[0] = (static_cast<std::uint32_t>(pool::NodeType::internal) << pool::k_node_address_bits) | 1u;
    nodes[9] = (static_cast<std::uint32_t>(pool::NodeType::internal) << pool::k_node_address_bits) | 1u;
    const std::uint32_t leaf_info[2] = {0, 0};
    const pool::Splat splat{};
    core::OctreeView v;
    v.nodes = nodes.data();
    v.node_count = static_cast<std::uint32_t>(nodes.size());
    v.leaf_info = leaf_info;
    v.filled_leaves = 1;
    v.splats = &splat;
    v.splat_count = 0;
    EXPECT_TRUE(rt::build_node_boxes(v, 1).boxes.empty());
    nodes[9] = core::k_empty_leaf_node;
    EXPECT_FALSE(rt::build_node_boxes(v, 1).boxes.empty());
}

// Macro-regions (core::MacroRegion, rt::build_macro_regions): an empty leaf is left through a box of
// free cells around it. The hits are bit-identical with and without them (with and without node
// boxes), fewer leaves are visited, and every region (each of an empty leaf's k_region_axes) holds no
// leaf with splats and stays in the root.
TEST_P(NodeBoxes, MacroRegionsKeepTheHitsAndSpareLeaves) {
    const BoxCase& c = GetParam();
    const TestModel m = make_model(room_with_ball(c.scale, {0, 0, 0}), {0, 0, 0}, 24, 10, c.replicate);
    const core::OctreeView plain = m.octree.view();
    const rt::MacroRegions mr = rt::build_macro_regions(plain, 2);
    ASSERT_EQ(mr.nodes.size(), plain.node_count);
    ASSERT_GT(mr.regions.size(), 100u);
    const rt::NodeBoxes nb = rt::build_node_boxes(plain, 2);
    for (bool boxes : {false, true}) {
        core::OctreeView a_view = plain;
        if (boxes) {
            a_view.node_boxes = nb.boxes.data();
            a_view.node_box_mask = nb.mask.data();
        }
        core::OctreeView b_view = a_view;
        b_view.nodes = mr.nodes.data();
        b_view.macro_regions = mr.regions.data();
        b_view.macro_region_count = static_cast<std::uint32_t>(mr.regions.size());
        core::WalkStats a_stats, b_stats;
        const std::size_t hits =
            same_hits(a_view, b_view, static_cast<float>(c.scale), 23, a_stats, b_stats).first;
        EXPECT_GT(hits, 1000u);
        EXPECT_EQ(b_stats.truncated, 0u);
        EXPECT_LT(b_stats.leaves, a_stats.leaves * 9 / 10) << "the regions spared under 10 % of the leaves";
        std::printf("%s, node boxes %s: leaves %u -> %u with macro-regions\n", c.name, boxes ? "on" : "off",
                    a_stats.leaves, b_stats.leaves);
    }
    // Every region: inside the root, and no leaf holding splats meets its interior (checked by
    // walking the tree down, in the cells of the leaf's level).
    std::vector<std::array<std::uint32_t, 4>> cell(plain.node_count, {0u, 0u, 0u, 0u});  // x, y, z, level
    for (std::uint32_t i = 0; i < plain.node_count; ++i)
        if (core::node_is_internal(plain.nodes[i]))
            for (std::uint32_t k = 0; k < 8; ++k)
                cell[core::node_addr(plain.nodes[i]) + k] = {2 * cell[i][0] + (k & 1),
                                                             2 * cell[i][1] + ((k >> 1) & 1),
                                                             2 * cell[i][2] + ((k >> 2) & 1), cell[i][3] + 1};
    std::size_t grown = 0;
    ASSERT_EQ(mr.regions.size() % core::k_region_axes, 0u);
    for (std::uint32_t i = 0; i < plain.node_count; ++i) {
        if (mr.nodes[i] == plain.nodes[i]) continue;  // no region: the pool's word
        ASSERT_FALSE(core::node_is_internal(plain.nodes[i]) || core::node_is_filled(plain.nodes[i])) << i;
        ASSERT_FALSE(core::node_is_internal(mr.nodes[i]) || core::node_is_filled(mr.nodes[i])) << i;
        ASSERT_NE(core::node_addr(mr.nodes[i]), 0u) << i;
        ASSERT_LT(core::node_addr(mr.nodes[i]), mr.regions.size() / core::k_region_axes) << i;
        const core::MacroRegion* rs = &mr.regions[core::k_region_axes * core::node_addr(mr.nodes[i])];
        bool some = false;
        for (std::uint32_t axis = 0; axis < core::k_region_axes; ++axis)
            some = some || (rs[axis].below[0] | rs[axis].below[1] | rs[axis].below[2] | rs[axis].above[0] |
                            rs[axis].above[1] | rs[axis].above[2]) != 0;
        ASSERT_TRUE(some) << i;
        ++grown;
        for (std::uint32_t axis = 0; axis < core::k_region_axes; ++axis) {
            const core::MacroRegion& r = rs[axis];
            const std::uint32_t l = cell[i][3];
            double lo[3], hi[3];  // the region in root units
            for (int a = 0; a < 3; ++a) {
                ASSERT_LE(r.below[a], cell[i][a]);
                ASSERT_LT(cell[i][a] + r.above[a], 1u << l);
                lo[a] = std::ldexp(double(cell[i][a] - r.below[a]), -int(l));
                hi[a] = std::ldexp(double(cell[i][a] + r.above[a] + 1), -int(l));
            }
            for (std::uint32_t j = 0; j < plain.node_count; ++j) {
                if (!core::node_is_filled(plain.nodes[j])) continue;
                std::uint32_t b, e;
                core::leaf_splats(plain, plain.nodes[j], b, e);
                if (b == e) continue;
                bool meets = true;
                for (int a = 0; a < 3; ++a) {
                    const double clo = std::ldexp(double(cell[j][a]), -int(cell[j][3]));
                    const double chi = std::ldexp(double(cell[j][a] + 1), -int(cell[j][3]));
                    meets = meets && clo < hi[a] && chi > lo[a];
                }
                ASSERT_FALSE(meets) << "region " << axis << " of node " << i << " meets filled leaf " << j;
            }
        }
        if (grown > 400) break;  // brute force: enough of them
    }
    EXPECT_GT(grown, 100u);
}

// rt::LoadOptions::empty_space (prt-play and prt-bench --empty-space): every way to pass empty space
// renders the same image, bit for bit, on a mirror room with a ball (shadows and four bounces);
// macro-regions and node boxes each visit fewer leaves than neither; an unknown name is an error.
TEST(EmptySpace, EveryWalkRendersTheSameImage) {
    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    sc.materials[0].reflectivity = 0.4f;
    sc.materials[0].diffuse_reflectance = 0.6f;
    sc.camera.position = {0.5, 0.3, 0.8};
    sc.camera.look_at = {-1, -1, -1};
    sc.camera.fov_y_degrees = 70;
    scene::PointLight pl;
    pl.position = {0.3, 0.8, 0.2};
    sc.point_lights.push_back(pl);
    sc.render.max_bounces = 4;
    const auto pool = make_pool(make_model(room_with_ball(1.0, {0, 0, 0}), {0, 0, 0}, 24, 10, true));
    auto backend = cpu::make_cpu_backend(2);
    std::vector<std::uint32_t> ref;
    std::uint64_t leaves[4] = {};
    const char* walks[4] = {"none", "boxes", "regions", "both"};
    for (int k = 0; k < 4; ++k) {
        rt::LoadOptions lo;
        lo.empty_space = walks[k];
        const rt::RenderScene rs = rt::RenderScene::from_pools(sc, {pool}, lo);
        EXPECT_EQ(rs.models()[0].view.octree.node_boxes != nullptr, k == 1 || k == 3) << walks[k];
        EXPECT_EQ(rs.models()[0].view.octree.macro_regions != nullptr, k >= 2) << walks[k];
        backend->set_scene(rs.view());
        rt::FrameRequest req;
        scene::Camera c = rs.scene().camera;
        c.width = c.height = 96;
        req.camera = rs.camera(c);
        req.params = rs.params();
        req.width = req.height = 96;
        rt::Image img;
        const rt::FrameStats st = backend->render(req, img);
        leaves[k] = st.leaves;
        if (k == 0)
            ref = img.rgba8;
        else
            EXPECT_TRUE(img.rgba8 == ref) << walks[k] << ": the image differs from the plain walk's";
    }
    EXPECT_LT(leaves[1], leaves[0]);
    EXPECT_LT(leaves[2], leaves[0] * 3 / 4) << "macro-regions spared under a quarter of the leaves";
    std::printf("leaves: none %llu, boxes %llu, regions %llu, both %llu\n", (unsigned long long)leaves[0],
                (unsigned long long)leaves[1], (unsigned long long)leaves[2], (unsigned long long)leaves[3]);
    rt::LoadOptions bad;
    bad.empty_space = "everything";
    EXPECT_THROW(rt::RenderScene::from_pools(sc, {pool}, bad), Error);
}

}  // namespace
}  // namespace prt::test
