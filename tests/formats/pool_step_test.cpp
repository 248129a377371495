// prt::tool::PoolStep (formats/include/prt/pool_step.h), run in-process: the standard options and
// their exit codes, carry-over of INPUT's sections, the provenance record, the atomic write (nothing
// written on error), --stats-json, the optional in-place -o, and no -o where a run writes none.
#include "prt/pool_step.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "point_cloud.h"
#include "prt/tool.h"
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
                 bool optional_output = false, bool* body_ran = nullptr) {
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
                if (body_ran) *body_ran = true;
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

TEST_F(PoolStepTest, ProvenanceTagIsRecordedInTheParameters) {
    ASSERT_EQ(run_step({path("in.pool"), "-o", path("out.pool"), "-q", "--provenance-tag",
                        R"({"input_xxh3": "00ff", "args": ["-k", "8"]})"}),
              0);
    const nlohmann::json prov =
        nlohmann::json::parse(pool::PoolFile::open(path("out.pool")).provenance_json());
    ASSERT_EQ(prov.size(), 2u);
    EXPECT_EQ(prov[1]["parameters"]["radius"], 0.5);  // the step's own parameters stay
    EXPECT_EQ(prov[1]["parameters"]["tag"]["input_xxh3"], "00ff");
    EXPECT_EQ(prov[1]["parameters"]["tag"]["args"][1], "8");
    EXPECT_FALSE(prov[0]["parameters"].contains("tag"));
    // Without the option no tag; a tag that is not JSON is a usage error and writes nothing.
    ASSERT_EQ(run_step({path("in.pool"), "-o", path("plain.pool"), "-q"}), 0);
    EXPECT_FALSE(
        nlohmann::json::parse(pool::PoolFile::open(path("plain.pool")).provenance_json())[1]["parameters"]
            .contains("tag"));
    EXPECT_EQ(run_step({path("in.pool"), "-o", path("bad.pool"), "--provenance-tag", "{not json"}),
              k_exit_usage_error);
    EXPECT_FALSE(fs::exists(path("bad.pool")));
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
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_step({path("in.pool")}), k_exit_usage_error);  // no -o: one line naming the option
    EXPECT_EQ(testing::internal::GetCapturedStderr(),
              "prt-test-step: error: --output is required (see --help)\n");
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

TEST_F(PoolStepTest, OutputUnusedWhereTheStepSaysSo) {
    // A step whose --dry runs write no OUTPUT (as prt-bricks --stage cells): there -o may be left
    // out, and one given is ignored with a note (unless --quiet) and not checked; every other run
    // of the same step still needs -o, with the usual usage error.
    std::string err, out;
    const auto run_dry_step = [&](std::vector<std::string> args) {
        std::vector<char*> argv{const_cast<char*>("prt-test-step")};
        for (std::string& a : args) argv.push_back(a.data());
        bool dry = false;
        out = "(the body did not run)";
        tool::PoolStep step("prt-test-step", "A test step");
        testing::internal::CaptureStderr();
        const int code = step.run(
            int(argv.size()), argv.data(),
            [&](CLI::App& app) {
                app.add_flag("--dry", dry, "Write nothing");
                step.output_unused_when(
                    [&] { return dry ? std::string("--dry writes nothing") : std::string(); });
            },
            [&](tool::PoolStep& s) {
                out = s.output_path();
                if (dry) return;
                s.writer().add_array(pool::SectionType::radii, std::vector<float>(10, 1.0f));
                s.write(nlohmann::json::object());
            });
        err = testing::internal::GetCapturedStderr();
        return code;
    };
    EXPECT_EQ(run_dry_step({path("in.pool"), "--dry"}), k_exit_ok);
    EXPECT_EQ(out, "");
    EXPECT_EQ(err, "");
    EXPECT_EQ(run_dry_step({path("in.pool"), "--dry", "-o", path("no/such/out.pool")}), k_exit_ok);
    EXPECT_EQ(out, "");
    EXPECT_EQ(err, "prt-test-step: -o " + path("no/such/out.pool") + " ignored: --dry writes nothing\n");
    EXPECT_EQ(run_dry_step({path("in.pool"), "-q", "--dry", "-o", path("out.pool")}), k_exit_ok);
    EXPECT_EQ(err, "");
    EXPECT_FALSE(fs::exists(path("out.pool")));
    EXPECT_EQ(run_dry_step({path("in.pool")}), k_exit_usage_error);
    EXPECT_EQ(out, "(the body did not run)");
    EXPECT_EQ(err, "prt-test-step: error: --output is required (see --help)\n");
    EXPECT_EQ(run_dry_step({path("in.pool"), "-q", "-o", path("out.pool")}), k_exit_ok) << err;
    EXPECT_EQ(out, path("out.pool"));
    EXPECT_EQ(pool::PoolFile::open(path("out.pool")).array<float>(pool::SectionType::radii).size(), 10u);
}

TEST_F(PoolStepTest, InputUnusedWhereTheStepSaysSo) {
    // A step whose --dry runs never read INPUT (as prt-bricks --stage cells): there INPUT need not
    // exist; every other run of the same step still refuses a missing INPUT before its work.
    std::string err;
    const auto run_step_without_input = [&](std::vector<std::string> args, bool& ran) {
        std::vector<char*> argv{const_cast<char*>("prt-test-step")};
        for (std::string& a : args) argv.push_back(a.data());
        bool dry = false;
        ran = false;
        tool::PoolStep step("prt-test-step", "A test step");
        testing::internal::CaptureStderr();
        const int code = step.run(
            int(argv.size()), argv.data(),
            [&](CLI::App& app) {
                app.add_flag("--dry", dry, "Read nothing");
                step.input_unused_when(
                    [&] { return dry ? std::string("--dry reads nothing") : std::string(); });
            },
            [&](tool::PoolStep&) { ran = true; });
        err = testing::internal::GetCapturedStderr();
        return code;
    };
    bool ran = false;
    EXPECT_EQ(run_step_without_input({path("missing.pool"), "--dry", "-o", path("out.pool")}, ran), k_exit_ok)
        << err;
    EXPECT_TRUE(ran);
    EXPECT_EQ(err, "");
    EXPECT_EQ(run_step_without_input({path("missing.pool"), "-o", path("out.pool")}, ran),
              k_exit_runtime_error);
    EXPECT_FALSE(ran);
    EXPECT_EQ(err, "prt-test-step: error: " + path("missing.pool") + ": no such file\n");
}

TEST_F(PoolStepTest, UnwritableOutputIsRefusedBeforeTheWork) {
    const auto refused = [&](std::vector<std::string> args, const std::string& named) {
        SCOPED_TRACE(named);
        bool ran = false;
        testing::internal::CaptureStderr();
        const int code = run_step(std::move(args), {}, {}, false, &ran);
        const std::string err = testing::internal::GetCapturedStderr();
        EXPECT_EQ(code, k_exit_runtime_error);
        EXPECT_FALSE(ran) << "the body ran before the output was checked";
        EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
        EXPECT_NE(err.find("prt-test-step: error: " + named + ": cannot write"), std::string::npos) << err;
    };
    // A folder that does not exist, a path that is a folder, --stats-json in a missing folder.
    refused({path("in.pool"), "-o", path("no/such/out.pool")}, path("no/such/out.pool"));
    fs::create_directory(path("taken"));
    refused({path("in.pool"), "-o", path("taken")}, path("taken"));
    refused({path("in.pool"), "-o", path("out.pool"), "--stats-json", path("none/s.json")},
            path("none/s.json"));
    EXPECT_FALSE(fs::exists(path("out.pool")));
    // A folder without write permission (root writes anyway: then only the message is checked above).
    if (::geteuid() != 0) {
        fs::create_directory(path("ro"));
        fs::permissions(path("ro"), fs::perms::owner_read | fs::perms::owner_exec);
        refused({path("in.pool"), "-o", path("ro/out.pool")}, path("ro/out.pool"));
        fs::permissions(path("ro"), fs::perms::owner_all);
    }
    // Nothing of the probe is left behind, and a writable output still works.
    ASSERT_EQ(run_step({path("in.pool"), "-o", path("out.pool"), "-q"}), 0);
    std::size_t files = 0;
    for (const auto& e : fs::directory_iterator(m_dir)) files += e.is_regular_file();
    EXPECT_EQ(files, 2u) << "in.pool and out.pool only";
}

TEST_F(PoolStepTest, MissingInputIsOneLineWithStatus1) {
    bool ran = false;
    testing::internal::CaptureStderr();
    const int code = run_step({path("none.pool"), "-o", path("out.pool")}, {}, {}, false, &ran);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(code, k_exit_runtime_error);
    EXPECT_FALSE(ran);
    EXPECT_EQ(err, "prt-test-step: error: " + path("none.pool") + ": no such file\n");
}

/// prt::tool::Progress with stderr not a terminal (captured to a file): whole lines, no '\r'.
TEST(Progress, LogLinesWhenStderrIsNotATerminal) {
    testing::internal::CaptureStderr();
    {
        tool::Progress bar("step", 100, false);
        const double t0 = tool::now_seconds();
        // 100 updates over about 2.5 s: a terminal would get ~10 '\r' updates.
        for (int i = 1; i <= 100; ++i) {
            while (tool::now_seconds() - t0 < 0.025 * i) ::usleep(2000);
            bar.update(std::uint64_t(i));
        }
        bar.finish();
    }
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(err.find('\r'), std::string::npos) << err;
    ASSERT_FALSE(err.empty());
    EXPECT_EQ(err.back(), '\n') << err;
    std::vector<std::string> lines;
    std::istringstream in(err);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    // At most one line a second (2.5 s: 2 progress lines at most) plus the final one.
    ASSERT_GE(lines.size(), 2u) << err;
    EXPECT_LE(lines.size(), 3u) << err;
    for (std::size_t i = 0; i + 1 < lines.size(); ++i) {
        EXPECT_EQ(lines[i].rfind("step: ", 0), 0u) << lines[i];
        EXPECT_NE(lines[i].find('%'), std::string::npos) << lines[i];
    }
    EXPECT_EQ(lines.back().rfind("step: done in ", 0), 0u) << lines.back();
}

TEST(Progress, LogLineRateLimit) {
    EXPECT_FALSE(tool::Progress::log_line_due(0.5, 50, 0));   // under a second: never
    EXPECT_TRUE(tool::Progress::log_line_due(1.0, 10, 0));    // a second and 10 %
    EXPECT_FALSE(tool::Progress::log_line_due(3.0, 19, 10));  // under 10 % more
    EXPECT_TRUE(tool::Progress::log_line_due(10.0, 11, 10));  // a slow step: every 10 s
}

}  // namespace
