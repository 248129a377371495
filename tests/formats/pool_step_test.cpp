// prt::tool::PoolStep (formats/include/prt/pool_step.h), run in-process: the standard options and
// their exit codes, carry-over of INPUT's sections, the provenance record, the atomic write (nothing
// written on error), --stats-json, and the optional in-place -o.
#include "prt/pool_step.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "point_cloud.h"
#include "runtime/tool_fixture.h"

namespace {

namespace fs = std::filesystem;
using namespace prt;

class PoolStepTest : public prt::test::FolderTest {
protected:
    PoolStepTest() : FolderTest("prt_pool_step_") {}
    void SetUp() override {
        FolderTest::SetUp();
        // A 10-point pool with positions and normals.
        pre::PointCloud c;
        for (int i = 0; i < 10; ++i) {
            c.positions.push_back({double(i), 0.0, 0.0});
            c.normals.push_back({0.f, 0.f, 1.f});
        }
        pool::PoolWriter w;
        pre::write_point_sections(c, w);
        w.add_provenance("pool_step_test", "0", R"({"made": "here"})");
        w.write(path("in.pool"));
    }

    /// Runs a step that adds a radii section of `radius` (or throws `error` when non-empty).
    int run_step(std::vector<std::string> args, tool::PoolStep::Help help = {}, const std::string& error = {},
                 bool optional_output = false) {
        std::vector<char*> argv{const_cast<char*>("prt-test-step")};
        for (std::string& a : args) argv.push_back(a.data());
        float radius = 0.5f;
        tool::PoolStep step("prt-test-step", "A test step", help);
        return step.run(
            int(argv.size()), argv.data(),
            [&](CLI::App& app) {
                app.add_option("--radius", radius, "Radius");
                if (optional_output) step.add_output(app, "Output (default: INPUT)");
            },
            [&](tool::PoolStep& s) {
                const auto positions = s.input().require<pool::Float3>(pool::SectionType::positions, "test");
                if (!error.empty()) s.about_input([&] { throw Error(error); });
                s.writer().add_array(pool::SectionType::radii, std::vector<float>(positions.size(), radius));
                s.write(nlohmann::json{{"radius", radius}});
                s.write_stats({{"points", positions.size()}});
            });
    }
};

TEST_F(PoolStepTest, CarriesOverAddsItsSectionAndProvenance) {
    ASSERT_EQ(run_step({path("in.pool"), "-o", path("out.pool"), "--radius", "0.25", "--quiet"}), 0);
    const pool::PoolFile out = pool::PoolFile::open(path("out.pool"));
    EXPECT_EQ(out.array<pool::Float3>(pool::SectionType::positions).size(), 10u);
    EXPECT_EQ(out.array<pool::Float3>(pool::SectionType::normals).size(), 10u);
    const auto radii = out.array<float>(pool::SectionType::radii);
    ASSERT_EQ(radii.size(), 10u);
    EXPECT_EQ(radii[3], 0.25f);
    const nlohmann::json prov = nlohmann::json::parse(out.provenance_json());
    ASSERT_TRUE(prov.is_array());
    ASSERT_EQ(prov.size(), 2u);  // the input's record, then the step's
    EXPECT_EQ(prov[0]["tool"], "pool_step_test");
    EXPECT_EQ(prov[1]["tool"], "prt-test-step");
    EXPECT_EQ(prov[1]["parameters"]["radius"], 0.25);
    EXPECT_FALSE(fs::exists(path("stats.json")));
}

TEST_F(PoolStepTest, StatsJsonNamesTheTool) {
    ASSERT_EQ(run_step({path("in.pool"), "-o", path("out.pool"), "--stats-json", path("stats.json"), "-q"}),
              0);
    std::ifstream in(path("stats.json"));
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["tool"], "prt-test-step");
    EXPECT_EQ(j["points"], 10);
}

TEST_F(PoolStepTest, UsageAndInputErrorsWriteNothing) {
    EXPECT_EQ(run_step({path("in.pool")}), k_exit_usage_error);         // no -o
    EXPECT_EQ(run_step({"-o", path("out.pool")}), k_exit_usage_error);  // no INPUT
    EXPECT_EQ(run_step({path("none.pool"), "-o", path("out.pool")}), k_exit_runtime_error);
    EXPECT_EQ(run_step({path("in.pool"), "-o", path("out.pool")}, {}, "bad data"), k_exit_runtime_error);
    EXPECT_FALSE(fs::exists(path("out.pool")));
}

TEST_F(PoolStepTest, LeftOutOptionsAreUsageErrors) {
    const tool::PoolStep::Help no_stats{.stats = ""};
    EXPECT_EQ(run_step({path("in.pool"), "-o", path("out.pool"), "--stats-json", path("s.json")}, no_stats),
              k_exit_usage_error);
    EXPECT_FALSE(fs::exists(path("out.pool")));
}

TEST_F(PoolStepTest, OptionalOutputRewritesInputInPlace) {
    const tool::PoolStep::Help in_place{.output = ""};
    ASSERT_EQ(run_step({path("in.pool"), "-q"}, in_place, {}, true), 0);
    const pool::PoolFile out = pool::PoolFile::open(path("in.pool"));
    EXPECT_EQ(out.array<float>(pool::SectionType::radii).size(), 10u);
}

}  // namespace
