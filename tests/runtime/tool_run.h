// Test-only helpers: run a built tool (build/bin) with arguments, capturing its exit code, stdout and
// stderr (the end-to-end tests of prt-play and prt-bench).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <string>

namespace prt::test {

struct ToolRun {
    int code;
    std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// Runs `prefix PRT_BIN_DIR/tool args` through the shell with stdout and stderr in files in `dir`.
/// `prefix` wraps the tool (e.g. "xvfb-run -a").
inline ToolRun run_tool(const std::string& tool, const std::string& args, const std::filesystem::path& dir,
                        const std::string& prefix = {}) {
    const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string cmd = (prefix.empty() ? std::string() : prefix + " ") + std::string(PRT_BIN_DIR) + "/" +
                            tool + " " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

/// Number of lines (newlines) in `s`.
inline int lines(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

/// `err` (a tool's stderr) is one line holding each of `words`.
inline void expect_one_line(const std::string& err, std::initializer_list<const char*> words) {
    EXPECT_EQ(lines(err), 1) << err;
    for (const char* w : words) EXPECT_NE(err.find(w), std::string::npos) << w << ": " << err;
}

/// Whether `program` is on the PATH.
inline bool on_path(const std::string& program) {
    return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0;
}

/// How a test runs a windowed tool: directly on the X display in $DISPLAY when one is set (e.g.
/// an Xvfb started with the NVIDIA GLX vendor library on the GPU machine), else under xvfb-run
/// with a 24-bit screen of `screen` (xvfb-run's default is 8-bit; -a picks a free display
/// number); nullopt when neither exists.
inline std::optional<std::string> display_prefix(const std::string& screen = "640x480") {
    const char* display = std::getenv("DISPLAY");
    if (display != nullptr && *display != '\0') return std::string();
    if (on_path("xvfb-run")) return "xvfb-run -a -s '-screen 0 " + screen + "x24'";
    return std::nullopt;
}

}  // namespace prt::test
