// Test-only: the fixtures of the end-to-end tests. FolderTest: a fresh folder per test, removed
// after it. ToolTest (tests/preprocess/*/tool_test.cpp): that folder, and run() keeping a tool's
// exit code, stdout and stderr.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <utility>

#include "runtime/tool_run.h"

namespace prt::test {

class FolderTest : public ::testing::Test {
protected:
    /// `prefix`: the test folders' name before "PID_TEST".
    explicit FolderTest(std::string prefix) : m_prefix(std::move(prefix)) {}

    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = std::filesystem::temp_directory_path() /
                (m_prefix + std::to_string(::getpid()) + "_" + info->name());
        std::filesystem::remove_all(m_dir);
        std::filesystem::create_directories(m_dir);
    }
    void TearDown() override {
        if (!m_dir.empty()) std::filesystem::remove_all(m_dir);
    }
    std::string path(const std::string& name) const { return (m_dir / name).string(); }

    std::string m_prefix;
    std::filesystem::path m_dir;
};

class ToolTest : public FolderTest {
protected:
    /// `tool`: the program in PRT_BIN_DIR; `prefix`: the test folders' name before "PID_TEST".
    ToolTest(std::string tool, std::string prefix) : FolderTest(std::move(prefix)), m_name(std::move(tool)) {}

    void SetUp() override {
        m_tool = std::filesystem::path(PRT_BIN_DIR) / m_name;
        if (!std::filesystem::exists(m_tool)) GTEST_SKIP() << m_name << " is not built in " << PRT_BIN_DIR;
        FolderTest::SetUp();
    }
    /// Runs the tool (tool_run.h), keeping its output for the checks.
    int run(const std::string& args) {
        const ToolRun r = run_tool(m_name, args, m_dir);
        m_stdout = r.out;
        m_stderr = r.err;
        return r.code;
    }

    std::string m_name;
    std::filesystem::path m_tool;
    std::string m_stdout, m_stderr;
};

}  // namespace prt::test
