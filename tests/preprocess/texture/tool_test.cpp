// prt-texture end to end (PRT_BIN_DIR/prt-texture): a textured plane gets the image's quadrant
// colors where the documented projection puts them, other sections and provenance are carried
// over, the pool is rewritten in place by default, and bad input (an unreadable image, a pool
// without normals) gives one line naming the file, exit 1, and leaves the pool byte for byte as it was.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "point_cloud.h"
#include "preprocess/cloud_pool.h"
#include "prt/formats/pool.h"
#include "prt/runtime/image.h"
#include "runtime/tool_fixture.h"

namespace {

namespace fs = std::filesystem;
using namespace prt;

class TextureTool : public prt::test::ToolTest {
protected:
    TextureTool() : ToolTest("prt-texture", "prt_texture_tool_") {}

    /// The unit square z = 5 (x, y in [0, 1], 11 x 11 points, normals +z, grey colors, radii),
    /// placed far from the world origin in x so the local frame matters.
    std::string plane_pool(const std::string& name, bool normals = true) {
        pre::PointCloud c;
        for (int i = 0; i <= 10; ++i)
            for (int j = 0; j <= 10; ++j) {
                c.positions.push_back({1e5 + i / 10.0, j / 10.0, 5.0});
                if (normals) c.normals.push_back({0, 0, 1});
                c.colors.push_back({128, 128, 128, 200});
                c.radii.push_back(0.08f);
            }
        return prt::test::write_cloud_pool(c, path(name));
    }
    /// An 8 x 8 PFM (linear floats): quadrants top-left red, top-right green, bottom-left blue,
    /// bottom-right white.
    std::string quadrant_image(const std::string& name) {
        rt::Image img;
        img.resize(8, 8);
        for (std::uint32_t y = 0; y < 8; ++y)
            for (std::uint32_t x = 0; x < 8; ++x) {
                const bool right = x >= 4, top = y < 4;
                const float c[3] = {top && !right ? 1.0f : (!top && right ? 1.0f : 0.0f),
                                    top && right ? 1.0f : (!top && right ? 1.0f : 0.0f), !top ? 1.0f : 0.0f};
                for (int k = 0; k < 3; ++k) img.rgb[(y * 8 + x) * 3 + k] = c[k];
            }
        rt::write_pfm(path(name), img, 1.0f);
        return path(name);
    }
};

TEST_F(TextureTool, PlaneGetsTheQuadrantsWhereTheProjectionPutsThem) {
    const std::string pool = plane_pool("plane.pool");
    const std::string img = quadrant_image("quad.pfm");
    ASSERT_EQ(run(pool + " --image " + img + " --scale 1 -o " + path("out.pool")), 0) << m_stderr;
    const pool::PoolFile out = pool::PoolFile::open(path("out.pool"));
    const pre::PointCloud c = pre::read_point_sections(out);
    ASSERT_EQ(c.colors.size(), 121u);
    int checked = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        // z plane: u = x - x_min, v = y - y_min, one repeat per unit; v = 1 is the image's top.
        const double u = c.positions[i][0] - 1e5, v = c.positions[i][1];
        const bool inside = (u > 0.05 && u < 0.45) || (u > 0.55 && u < 0.95);
        const bool inside_v = (v > 0.05 && v < 0.45) || (v > 0.55 && v < 0.95);
        if (!inside || !inside_v) continue;  // texels of two quadrants blend there
        const bool right = u > 0.5, top = v > 0.5;
        const pool::Rgba8 want =
            top ? (right ? pool::Rgba8{0, 255, 0, 200} : pool::Rgba8{255, 0, 0, 200})
                : (right ? pool::Rgba8{255, 255, 255, 200} : pool::Rgba8{0, 0, 255, 200});
        EXPECT_EQ(c.colors[i].r, want.r) << "u " << u << " v " << v;
        EXPECT_EQ(c.colors[i].g, want.g) << "u " << u << " v " << v;
        EXPECT_EQ(c.colors[i].b, want.b) << "u " << u << " v " << v;
        EXPECT_EQ(c.colors[i].a, want.a) << "alpha is carried over";
        ++checked;
    }
    EXPECT_EQ(checked, 64);
    // Everything else carried over, provenance appended.
    const pool::PoolFile in = pool::PoolFile::open(pool);
    for (pool::SectionType t :
         {pool::SectionType::positions, pool::SectionType::normals, pool::SectionType::radii}) {
        const auto a = in.bytes(*in.find(t)), b = out.bytes(*out.find(t));
        ASSERT_EQ(a.size(), b.size());
        EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin()));
    }
    const nlohmann::json prov = nlohmann::json::parse(out.provenance_json());
    ASSERT_EQ(prov.size(), 2u);
    EXPECT_EQ(prov[1]["tool"], "prt-texture");
    const nlohmann::json& params = prov[1]["parameters"];
    EXPECT_EQ(params["scale"], 1.0);
    EXPECT_EQ(params["blend"], "replace");
    EXPECT_EQ(params["image"], fs::absolute(img).lexically_normal().string());
}

TEST_F(TextureTool, InPlaceByDefaultWithDefaultScaleAndQuiet) {
    const std::string pool = plane_pool("plane.pool");
    const std::string img = quadrant_image("quad.pfm");
    ASSERT_EQ(run(pool + " --image " + img + " --quiet"), 0) << m_stderr;
    EXPECT_TRUE(m_stderr.empty()) << m_stderr;
    const pool::PoolFile out = pool::PoolFile::open(pool);
    const nlohmann::json prov = nlohmann::json::parse(out.provenance_json());
    ASSERT_EQ(prov.size(), 2u);
    const nlohmann::json& params = prov[1]["parameters"];
    // Bounding box 1 x 1 x 0: diagonal sqrt 2, scale sqrt 2 / 4.
    EXPECT_NEAR(params["scale"].get<double>(), std::sqrt(2.0) / 4.0, 1e-6);
    EXPECT_TRUE(params["scale_auto"].get<bool>());
    for (const fs::directory_entry& e : fs::directory_iterator(m_dir))
        EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "left a temporary file: " << e.path();
}

TEST_F(TextureTool, BadImageLeavesThePoolUnchanged) {
    const std::string pool = plane_pool("plane.pool");
    const std::string before = test::slurp(pool);
    {
        std::ofstream bad(path("bad.png"), std::ios::binary);
        bad << "\x89PNG\r\n\x1a\n this is not a PNG body";
    }
    std::ofstream(path("bad.pfm")) << "PF\n8 8\n-1\nshort";
    for (const std::string& image : {path("bad.png"), path("bad.pfm"), path("missing.png")}) {
        SCOPED_TRACE(image);
        EXPECT_EQ(run(pool + " --image " + image), 1);
        EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;
        EXPECT_NE(m_stderr.find("prt-texture: error: "), std::string::npos) << m_stderr;
        EXPECT_NE(m_stderr.find(image), std::string::npos) << "the error names the image: " << m_stderr;
        EXPECT_EQ(test::slurp(pool), before) << "the pool changed";
    }
    // A bad second image stops the run before anything is written, too.
    const std::string good = quadrant_image("quad.pfm");
    EXPECT_EQ(run(pool + " --image " + good + " --image-z " + path("bad.png") + " -o " + path("out.pool")),
              1);
    EXPECT_FALSE(fs::exists(path("out.pool")));
    EXPECT_EQ(test::slurp(pool), before);
}

TEST_F(TextureTool, PoolWithoutNormalsAndBadUsage) {
    const std::string pool = plane_pool("flat.pool", false);
    const std::string img = quadrant_image("quad.pfm");
    const std::string before = test::slurp(pool);
    EXPECT_EQ(run(pool + " --image " + img), 1);
    EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;
    EXPECT_NE(m_stderr.find(pool), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("normals"), std::string::npos) << m_stderr;
    EXPECT_EQ(test::slurp(pool), before);
    EXPECT_EQ(run(pool), 2) << "--image is required";
    EXPECT_EQ(run(pool + " --image " + img + " --blend add"), 2);
    EXPECT_EQ(run(pool + " --image " + img + " --scale -1"), 2);
}

TEST_F(TextureTool, HelpDocumentsEveryOptionWithItsDefault) {
    ASSERT_EQ(run("--help"), 0);
    const std::string& help = m_stdout;
    for (const char* opt : {"--image", "--image-y", "--image-z", "--scale", "--sharpness", "--blend",
                            "--output", "--threads", "--quiet", "thesis 5.5"})
        EXPECT_NE(help.find(opt), std::string::npos) << opt;
    EXPECT_NE(help.find("diagonal / 4"), std::string::npos);
    EXPECT_NE(help.find("default 1"), std::string::npos);
    EXPECT_NE(help.find("default: rewrite POOL in place"), std::string::npos);
}

}  // namespace
