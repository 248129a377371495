// The MLS sections in a pool: round trip through PoolWriter / PoolFile, and validation of every
// cross-reference the traversal relies on (validate_mls): a bad pool is a one-line error naming
// the file and the section, never a crash or an endless loop.
#include "prt/formats/pool.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <functional>

#include "mls_bvh.h"
#include "mls_test_util.h"
#include "point_cloud.h"
#include "prt/error.h"
#include "prt/runtime/surface_pools.h"

namespace {

using namespace prt;
using namespace prt::mls_test;

struct Built {
    pre::PointCloud cloud;
    mls::MlsModel model;
};

Built built(std::size_t n = 800) {
    const PointSet s = fibonacci_sphere(n);
    Built b;
    for (std::size_t i = 0; i < n; ++i) {
        b.cloud.positions.push_back({s.positions[i].x, s.positions[i].y, s.positions[i].z});
        b.cloud.normals.push_back(s.normals[i]);
        b.cloud.radii.push_back(s.radii[i]);
    }
    b.model = build(s);
    return b;
}

/// A pool image with the point sections and the MLS sections of `m`, after `edit` changed them.
pool::PoolFile make_pool(const Built& b, const std::function<void(mls::MlsModel&)>& edit = {}) {
    mls::MlsModel m = b.model;
    if (edit) edit(m);
    pool::PoolWriter w;
    pre::write_point_sections(b.cloud, w);
    mls::write_mls_sections(std::move(m), w);
    return pool::PoolFile::from_bytes(w.serialize(), "test.pool");
}

void expect_error(const Built& b, const std::function<void(mls::MlsModel&)>& edit, const std::string& section,
                  const std::string& what) {
    const pool::PoolFile p = make_pool(b, edit);
    try {
        mls::validate_mls(p);
        FAIL() << "expected an error about " << what;
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("test.pool"), std::string::npos) << msg;
        EXPECT_NE(msg.find(section), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
}

TEST(MlsPool, RoundTripGivesTheSameSurface) {
    const Built b = built();
    const pool::PoolFile p = make_pool(b);
    EXPECT_TRUE(mls::has_mls(p));
    const core::MlsView v = rt::load_mls_view(p);
    EXPECT_EQ(v.node_count, b.model.nodes.size());
    EXPECT_EQ(v.ref_count, b.model.refs.size());
    EXPECT_EQ(v.splat_count, b.model.splats.size());
    EXPECT_EQ(v.depth, b.model.info.depth);
    const core::MlsView mem = mls::make_view(b.model);
    core::MlsHit h1, h2;
    core::MlsStats s1, s2;
    for (float y = -0.9f; y < 0.9f; y += 0.1f) {
        const bool a = core::trace_mls(v, {-3, y, 0.05f}, {1, 0, 0}, core::k_inf, false, {}, h1, s1);
        const bool c = core::trace_mls(mem, {-3, y, 0.05f}, {1, 0, 0}, core::k_inf, false, {}, h2, s2);
        ASSERT_EQ(a, c);
        if (a) {
            EXPECT_EQ(h1.t, h2.t);
        }
    }
    // A pool without the sections.
    pool::PoolWriter w;
    pre::write_point_sections(b.cloud, w);
    const pool::PoolFile plain = pool::PoolFile::from_bytes(w.serialize(), "plain.pool");
    EXPECT_FALSE(mls::has_mls(plain));
    try {
        mls::validate_mls(plain);
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("run prt-mls"), std::string::npos) << e.what();
    }
}

TEST(MlsPool, RejectsEveryBrokenCrossReference) {
    const Built b = built();
    auto first_inner = [](const mls::MlsModel& m) {
        for (std::size_t i = 0; i < m.nodes.size(); ++i)
            if (!pool::mls_node_is_leaf(m.nodes[i])) return i;
        return std::size_t(0);
    };
    auto first_filled_leaf = [](const mls::MlsModel& m) {
        for (std::size_t i = 0; i < m.nodes.size(); ++i)
            if (pool::mls_node_is_leaf(m.nodes[i]) && pool::mls_leaf_count(m.nodes[i]) > 0) return i;
        return std::size_t(0);
    };
    // A child pointing back to its parent: a cycle.
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const std::size_t i = first_inner(m);
            m.nodes[i].meta = (std::uint32_t(i) << 2) | pool::mls_node_axis(m.nodes[i]);
        },
        "mls_nodes", "not after it");
    // Children beyond the node array.
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            m.nodes[0].meta = (std::uint32_t(m.nodes.size()) << 2) | pool::mls_node_axis(m.nodes[0]);
        },
        "mls_nodes", "out of range");
    // A split plane outside its cell.
    expect_error(
        b, [&](mls::MlsModel& m) { m.nodes[0].payload = std::bit_cast<std::uint32_t>(1e9f); }, "mls_nodes",
        "outside its cell");
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            m.nodes[0].payload = std::bit_cast<std::uint32_t>(std::numeric_limits<float>::quiet_NaN());
        },
        "mls_nodes", "outside its cell");
    // A leaf's refs beyond mls_refs, or shared by two leaves.
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const std::size_t i = first_filled_leaf(m);
            m.nodes[i] = pool::make_mls_leaf(std::uint32_t(m.refs.size()) - 1, 5);
        },
        "mls_nodes", "beyond");
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const std::size_t i = first_filled_leaf(m);
            m.nodes[i] = pool::make_mls_leaf(0, pool::mls_leaf_count(m.nodes[i]) + 1);
        },
        "mls_nodes", "two leaves");
    // Refs out of range.
    expect_error(
        b, [&](mls::MlsModel& m) { m.refs[3] = std::uint32_t(m.splats.size()); }, "mls_refs", "out of range");
    // Splats: not finite, zero support, point index out of range.
    expect_error(
        b, [&](mls::MlsModel& m) { m.splats[2].position.y = std::numeric_limits<float>::infinity(); },
        "mls_splats", "not finite");
    expect_error(
        b, [&](mls::MlsModel& m) { m.splats[2].inv_support = 0.0f; }, "mls_splats", "support");
    expect_error(
        b, [&](mls::MlsModel& m) { m.splats[2].point = 5000; }, "mls_splats", "out of range");
    // Info disagreeing with the sections.
    expect_error(
        b, [&](mls::MlsModel& m) { m.info.node_count += 1; }, "mls_nodes", "mls_info says");
    expect_error(
        b, [&](mls::MlsModel& m) { m.info.depth += 1; }, "mls_nodes", "depth");
    expect_error(
        b, [&](mls::MlsModel& m) { m.info.depth = 70; }, "mls_info", "exceeds");
    expect_error(
        b, [&](mls::MlsModel& m) { m.info.leaf_count += 1; }, "mls_nodes", "leaves");
    expect_error(
        b, [&](mls::MlsModel& m) { m.info.root_lo[0] = std::numeric_limits<float>::quiet_NaN(); }, "mls_info",
        "root cell");
    // A node nobody reaches (an extra pair at the end).
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            m.nodes.push_back(pool::make_mls_leaf(0, 0));
            m.info.node_count += 1;
        },
        "mls_nodes", "not reachable");
    // Missing one of the four sections.
    {
        pool::PoolWriter w;
        pre::write_point_sections(b.cloud, w);
        mls::MlsModel m = b.model;
        mls::write_mls_sections(std::move(m), w);
        w.remove(pool::SectionType::mls_refs);
        const pool::PoolFile p = pool::PoolFile::from_bytes(w.serialize(), "test.pool");
        EXPECT_THROW(mls::validate_mls(p), Error);
    }
}

/// The BVH over the non-empty leaves (sections 52-53): every way it can disagree with the kd-tree
/// or fail to bound what lies under it is refused with one line; a pool without it (prt-mls
/// --no-bvh, or written before it) loads and traces the same surface through the kd walk.
TEST(MlsPool, RejectsABrokenBvh) {
    const Built b = built();
    ASSERT_GE(b.model.bvh_leaves.size(), 4u);
    auto leaf_child = [](const mls::MlsModel& m) {  // a node slot holding a leaf
        for (std::size_t i = 0; i < m.bvh_nodes.size(); ++i)
            for (int c = 0; c < 2; ++c)
                if (m.bvh_nodes[i].child[c].ref & pool::k_mls_bvh_leaf_bit) return std::pair{i, c};
        return std::pair{std::size_t(0), 0};
    };
    auto inner_child = [](const mls::MlsModel& m) {  // a node slot holding a node
        for (std::size_t i = 0; i < m.bvh_nodes.size(); ++i)
            for (int c = 0; c < 2; ++c)
                if (!(m.bvh_nodes[i].child[c].ref & pool::k_mls_bvh_leaf_bit)) return std::pair{i, c};
        return std::pair{std::size_t(0), 0};
    };
    expect_error(
        b, [&](mls::MlsModel& m) { m.bvh_nodes[0].child[inner_child(m).second].ref = 0; }, "mls_bvh_nodes",
        "not after it");
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const auto [i, c] = inner_child(m);
            m.bvh_nodes[i].child[c].ref = std::uint32_t(m.bvh_nodes.size());
        },
        "mls_bvh_nodes", "out of range");
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const auto [i, c] = leaf_child(m);
            m.bvh_nodes[i].child[c].ref = pool::k_mls_bvh_leaf_bit | std::uint32_t(m.bvh_leaves.size());
        },
        "mls_bvh_nodes", "out of range");
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const auto [i, c] = leaf_child(m);
            // Point another slot at the same leaf.
            for (std::size_t j = 0; j < m.bvh_nodes.size(); ++j)
                for (int k = 0; k < 2; ++k)
                    if ((j != i || k != c) && (m.bvh_nodes[j].child[k].ref & pool::k_mls_bvh_leaf_bit)) {
                        m.bvh_nodes[j].child[k].ref = m.bvh_nodes[i].child[c].ref;
                        return;
                    }
        },
        "mls_bvh_nodes", "reached twice");
    // Boxes: a leaf's box short of its supports, a node's short of its children's, NaN.
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const auto [i, c] = leaf_child(m);
            pool::MlsBvhChild& ch = m.bvh_nodes[i].child[c];
            ch.hi[1] = ch.lo[1] + 0.25f * (ch.hi[1] - ch.lo[1]);
        },
        "mls_bvh_nodes", "does not hold its cell's supports");
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            const auto [i, c] = inner_child(m);
            pool::MlsBvhChild& ch = m.bvh_nodes[i].child[c];
            ch.lo[0] = ch.hi[0];
        },
        "mls_bvh_nodes", "does not hold its children");
    expect_error(
        b, [&](mls::MlsModel& m) { m.bvh_nodes[0].child[1].lo[2] = std::numeric_limits<float>::quiet_NaN(); },
        "mls_bvh_nodes", "not finite");
    // Leaves: another cell, refs that are no kd leaf's, a count off by one.
    expect_error(
        b, [&](mls::MlsModel& m) { m.bvh_leaves[1].lo[0] -= 0.01f; }, "mls_bvh_leaves", "cell differs");
    expect_error(
        b, [&](mls::MlsModel& m) { m.bvh_leaves[1].first += 1; }, "mls_bvh_leaves", "no non-empty kd leaf");
    expect_error(
        b, [&](mls::MlsModel& m) { m.bvh_leaves[1].count += 1; }, "mls_bvh_leaves", "no non-empty kd leaf");
    // Counts and depth.
    expect_error(
        b, [&](mls::MlsModel& m) { m.bvh_nodes.push_back(m.bvh_nodes.back()); }, "mls_bvh_nodes",
        "BVH nodes");
    expect_error(
        b, [&](mls::MlsModel& m) { m.info.bvh_depth += 1; }, "mls_bvh_nodes", "BVH depth");
    expect_error(
        b, [&](mls::MlsModel& m) { m.info.bvh_depth = 70; }, "mls_info", "exceeds");
    expect_error(
        b,
        [&](mls::MlsModel& m) {
            m.bvh_nodes.clear();
            m.bvh_leaves.clear();
        },
        "mls_info", "without the BVH sections");
    {  // one of the two sections alone
        pool::PoolWriter w;
        pre::write_point_sections(b.cloud, w);
        mls::MlsModel m = b.model;
        mls::write_mls_sections(std::move(m), w);
        w.remove(pool::SectionType::mls_bvh_leaves);
        const pool::PoolFile p = pool::PoolFile::from_bytes(w.serialize(), "test.pool");
        EXPECT_THROW(mls::validate_mls(p), Error);
    }
    // Without the BVH: valid, and the kd walk finds the same roots.
    const pool::PoolFile with = make_pool(b);
    const pool::PoolFile without = make_pool(b, [](mls::MlsModel& m) {
        m.bvh_nodes.clear();
        m.bvh_leaves.clear();
        m.info.bvh_depth = 0;
    });
    const core::MlsView vb = rt::load_mls_view(with), vk = rt::load_mls_view(without);
    ASSERT_NE(vb.bvh_nodes, nullptr);
    ASSERT_EQ(vk.bvh_nodes, nullptr);
    int hits = 0;
    for (float y = -0.95f; y < 0.95f; y += 0.05f) {
        core::MlsHit h1, h2;
        core::MlsStats s1, s2;
        const bool a = core::trace_mls(vb, {-3, y, 0.05f}, {1, 0.01f, 0}, core::k_inf, false, {}, h1, s1);
        const bool c = core::trace_mls(vk, {-3, y, 0.05f}, {1, 0.01f, 0}, core::k_inf, false, {}, h2, s2);
        ASSERT_EQ(a, c);
        if (a) {
            ++hits;
            EXPECT_EQ(h1.t, h2.t);
        }
    }
    EXPECT_GT(hits, 30);
}

/// A deep chain of nodes (a valid tree) up to the depth limit traces without overflowing the
/// fixed stack; one level more is refused by the validation.
TEST(MlsPool, DepthLimitIsEnforced) {
    const Built b = built(300);
    auto chain = [&](std::uint32_t levels) {
        return [&, levels](mls::MlsModel& m) {
            // Replace the tree by a chain of splits along x at the root's centre, each with an
            // empty right child, ending in one leaf holding every splat.
            const float lo = m.info.root_lo[0], hi = m.info.root_hi[0];
            std::vector<pool::MlsNode> nodes(1);
            std::uint32_t at = 0;
            float right = hi;
            for (std::uint32_t l = 0; l < levels; ++l) {
                right = lo + (right - lo) * 0.9f;
                const auto left = std::uint32_t(nodes.size());
                nodes[at] = pool::make_mls_inner(std::bit_cast<std::uint32_t>(right), 0, left);
                nodes.push_back({});
                nodes.push_back(pool::make_mls_leaf(0, 0));
                at = left;
            }
            m.refs.resize(m.splats.size());
            for (std::uint32_t i = 0; i < m.refs.size(); ++i) m.refs[i] = i;
            nodes[at] = pool::make_mls_leaf(0, std::uint32_t(m.refs.size()));
            m.nodes = nodes;
            m.info.node_count = std::uint32_t(nodes.size());
            m.info.ref_count = std::uint32_t(m.refs.size());
            m.info.depth = levels;
            m.info.leaf_count = levels + 1;
            mls::build_mls_bvh(m);  // one non-empty leaf: no BVH
        };
    };
    const pool::PoolFile ok = make_pool(b, chain(pool::k_max_mls_depth));
    const core::MlsView v = rt::load_mls_view(ok);
    EXPECT_EQ(v.depth, pool::k_max_mls_depth);
    core::MlsHit h;
    core::MlsStats st;
    core::trace_mls(v, {-3, 0, 0}, {1, 0, 0}, core::k_inf, false, {}, h, st);
    EXPECT_EQ(st.truncated, 0u);
    const pool::PoolFile deep = make_pool(b, chain(pool::k_max_mls_depth + 1));
    EXPECT_THROW(mls::validate_mls(deep), Error);
}

}  // namespace
