// The ISO sections in a pool: round trip through PoolWriter / PoolFile (rt::load_iso_view), and
// validate_iso's validation of corrupted sections (one-line errors naming the file and the section, never a
// crash).
#include "prt/formats/pool.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "iso_test_util.h"
#include "point_cloud.h"
#include "prt/runtime/surface_pools.h"

namespace {

using namespace prt;
using namespace prt::iso_test;

/// A pool image with the points of `s` and a built ISO (both leaf arrays).
iso::IsoModel small_model() {
    const PointSet s = synth_points(sphere_shape(1.0), 5000, 0.0, true);
    iso::BuildOptions o;
    o.max_level = 6;
    o.storage = iso::Storage::both;
    o.threads = 2;
    return iso::build_iso(s.input(), o);
}

pool::PoolFile to_pool(const iso::IsoModel& model, const char* label = "test.pool") {
    pool::PoolWriter w;
    pool::ModelInfo info{};
    info.point_count = 0;
    w.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
    iso::IsoModel copy = model;
    iso::write_iso_sections(std::move(copy), w);
    return pool::PoolFile::from_bytes(w.serialize(), label);
}

std::string load_error(const iso::IsoModel& model) {
    try {
        const pool::PoolFile p = to_pool(model);
        iso::validate_iso(p);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST(IsoPool, RoundTripKeepsEveryByte) {
    const iso::IsoModel m = small_model();
    const pool::PoolFile p = to_pool(m);
    EXPECT_TRUE(iso::has_iso(p));
    const core::IsoView v = rt::load_iso_view(p);
    EXPECT_EQ(v.leaf_count, m.info.leaf_count);
    EXPECT_EQ(v.tree.node_count, m.nodes.size());
    EXPECT_EQ(v.use_q8, 1u);
    EXPECT_EQ(0, std::memcmp(v.leaves_q8, m.leaves_q8.data(), m.leaves_q8.size() * sizeof(pool::IsoLeafQ8)));
    EXPECT_EQ(0,
              std::memcmp(v.leaves_f32, m.leaves_f32.data(), m.leaves_f32.size() * sizeof(pool::IsoLeafF32)));
    EXPECT_EQ(rt::load_iso_view(p, false).use_q8, 0u);
    // Both views trace the same as the in-memory model.
    const core::IsoView mv = iso::make_view(m);
    core::IsoHit a, b;
    core::IsoStats st;
    ASSERT_TRUE(core::trace_iso(v, core::Vec3{0.2f, 0.1f, 3}, core::Vec3{0, 0, -1}, 9.0f, false, {}, a, st));
    ASSERT_TRUE(core::trace_iso(mv, core::Vec3{0.2f, 0.1f, 3}, core::Vec3{0, 0, -1}, 9.0f, false, {}, b, st));
    EXPECT_EQ(a.t, b.t);
    // q8 only: the f32 array goes away (also when it was carried over).
    iso::IsoModel q = m;
    q.info.flags &= ~pool::k_iso_has_f32;
    q.leaves_f32.clear();
    const pool::PoolFile pq = to_pool(q);
    EXPECT_FALSE(pq.has(pool::SectionType::iso_leaves_f32));
    EXPECT_EQ(rt::load_iso_view(pq, false).use_q8, 1u);  // falls back to the array present
}

TEST(IsoPool, CorruptSectionsAreRefusedWithOneLine) {
    const iso::IsoModel good = small_model();
    ASSERT_EQ(load_error(good), "");
    auto expect = [&](iso::IsoModel m, const std::string& section, const std::string& what) {
        const std::string e = load_error(m);
        EXPECT_NE(e.find("test.pool: section " + section), std::string::npos) << e;
        EXPECT_NE(e.find(what), std::string::npos) << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    };
    // find an internal node and a filled leaf
    std::size_t internal = 0, leaf = 0;
    for (std::size_t i = 0; i < good.nodes.size(); ++i) {
        if (pool::node_type(good.nodes[i]) == pool::NodeType::internal && i > 0 && !internal) internal = i;
        if (pool::node_type(good.nodes[i]) == pool::NodeType::filled_leaf && !leaf) leaf = i;
    }
    ASSERT_GT(internal, 0u);
    ASSERT_GT(leaf, 0u);
    {
        iso::IsoModel m = good;
        m.nodes[internal] = pool::make_node(pool::NodeType::internal, 1);  // points backwards
        expect(m, "iso_nodes", "not after it");
    }
    {
        iso::IsoModel m = good;
        m.nodes[internal] = pool::make_node(pool::NodeType::internal, std::uint32_t(m.nodes.size() - 4));
        expect(m, "iso_nodes", "out of range");
    }
    {
        iso::IsoModel m = good;
        m.nodes[leaf] = pool::make_node(pool::NodeType::filled_leaf, m.info.leaf_count);
        expect(m, "iso_nodes", "out of range");
    }
    {
        iso::IsoModel m = good;
        std::size_t other = leaf + 1;
        while (pool::node_type(m.nodes[other]) != pool::NodeType::filled_leaf) ++other;
        m.nodes[other] = m.nodes[leaf];
        expect(m, "iso_nodes", "addressed twice");
    }
    {
        iso::IsoModel m = good;
        m.nodes[leaf] = 3u << 30;
        expect(m, "iso_nodes", "invalid node type");
    }
    {
        iso::IsoModel m = good;
        m.leaves_q8.pop_back();
        expect(m, "iso_leaves_q8", "leaves but iso_info says");
    }
    {
        iso::IsoModel m = good;
        m.leaves_f32[3].value[2] = std::numeric_limits<float>::quiet_NaN();
        expect(m, "iso_leaves_f32", "not finite");
    }
    {
        iso::IsoModel m = good;
        m.info.root_size = 0;
        expect(m, "iso_info", "root edge");
    }
    {
        iso::IsoModel m = good;
        m.info.depth = m.info.depth - 1;
        expect(m, "iso_nodes", "deepest filled leaf");
    }
    {
        iso::IsoModel m = good;
        m.info.max_level = pool::k_max_iso_level + 1;
        expect(m, "iso_info", "levels");
    }
    {
        iso::IsoModel m = good;
        m.info.node_count += 1;
        expect(m, "iso_nodes", "nodes but iso_info says");
    }
    {
        // The f32 flag without its array.
        pool::PoolWriter w;
        pool::ModelInfo info{};
        w.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
        iso::IsoModel m = good;
        w.add_array(pool::SectionType::iso_info, std::vector<pool::IsoInfo>{m.info});
        w.add_array(pool::SectionType::iso_nodes, m.nodes);
        w.add_array(pool::SectionType::iso_leaves_q8, m.leaves_q8);
        const pool::PoolFile p = pool::PoolFile::from_bytes(w.serialize(), "test.pool");
        try {
            iso::validate_iso(p);
            ADD_FAILURE() << "accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("iso_leaves_f32 missing"), std::string::npos) << e.what();
        }
    }
    {
        // No ISO at all.
        pool::PoolWriter w;
        pool::ModelInfo info{};
        w.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
        const pool::PoolFile p = pool::PoolFile::from_bytes(w.serialize(), "test.pool");
        EXPECT_FALSE(iso::has_iso(p));
        try {
            iso::validate_iso(p);
            ADD_FAILURE() << "accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("run prt-iso"), std::string::npos) << e.what();
        }
    }
}

TEST(IsoPool, SectionNamesAndVersions) {
    EXPECT_STREQ(pool::section_name(pool::SectionType::iso_info), "iso_info");
    EXPECT_STREQ(pool::section_name(pool::SectionType::iso_nodes), "iso_nodes");
    EXPECT_STREQ(pool::section_name(pool::SectionType::iso_leaves_q8), "iso_leaves_q8");
    EXPECT_STREQ(pool::section_name(pool::SectionType::iso_leaves_f32), "iso_leaves_f32");
    EXPECT_EQ(pool::section_version(pool::SectionType::iso_leaves_q8), 1u);
    EXPECT_EQ(sizeof(pool::IsoLeafQ8), 56u);  // thesis 4.4
}

}  // namespace
