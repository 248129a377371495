// Shared helpers of the prt-synth tests: double-precision vector arithmetic written out here (not
// the library's), the analytic shapes the tests sample (sized per test file), and runs of the
// prt-synth binary (a temporary folder per run, its --help text).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

#include "analytic.h"

/// Skips the test where prt-synth is not built (the end-to-end tests run it).
#define PRT_NEED_SYNTH()                                                            \
    if (!std::filesystem::exists(std::filesystem::path(PRT_BIN_DIR) / "prt-synth")) \
    GTEST_SKIP() << "prt-synth not built in " << PRT_BIN_DIR

namespace prt::synth_test {

using synth::Vec3;

inline Vec3 sub(const Vec3& a, const Vec3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline double dot(const Vec3& a, const Vec3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline double len(const Vec3& a) {
    return std::sqrt(dot(a, a));
}

/// The sizes of every analytic shape a test file uses (the room is always the 2 m standard one).
struct ShapeSizes {
    double sphere_radius;
    synth::Torus torus;
    double cube_edge;
    double plane_size;
    synth::Ring ring{};
};

/// A shape of `kind` with every kind's parameters set from `z`.
inline synth::Shape make_shape(synth::ShapeKind kind, const ShapeSizes& z) {
    synth::Shape s;
    s.kind = kind;
    s.sphere.radius = z.sphere_radius;
    s.torus = z.torus;
    s.cube.edge = z.cube_edge;
    s.plane.size = z.plane_size;
    s.room = synth::Room::standard(2.0);
    s.ring = z.ring;
    return s;
}

/// What a run of the prt-synth binary gave: its exit code and stderr.
struct ToolRun {
    int exit_code = -1;
    std::string err;
};

/// A fresh temporary folder (named from `prefix`, the process and a counter), removed afterwards,
/// in which prt-synth runs.
class ToolDir {
public:
    explicit ToolDir(const std::string& prefix) {
        static std::atomic<int> counter{0};
        m_path = std::filesystem::temp_directory_path() /
                 (prefix + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        std::filesystem::create_directories(m_path);
    }
    ~ToolDir() {
        std::error_code ec;
        std::filesystem::remove_all(m_path, ec);
    }
    ToolDir(const ToolDir&) = delete;
    ToolDir& operator=(const ToolDir&) = delete;
    const std::filesystem::path& path() const { return m_path; }

    /// Runs prt-synth (from PRT_BIN_DIR) with `args` (already quoted for the shell).
    ToolRun run(const std::string& args) const {
        const std::filesystem::path err = m_path / "stderr.txt";
        std::string cmd = "'";  // built by appending: GCC 12 warns (-Wrestrict) on "'" + string
        cmd += (std::filesystem::path(PRT_BIN_DIR) / "prt-synth").string();
        cmd += "' " + args + " > /dev/null 2> '" + err.string() + "'";
        const int status = std::system(cmd.c_str());
        ToolRun r;
        r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        std::ifstream in(err);
        std::stringstream s;
        s << in.rdbuf();
        r.err = s.str();
        return r;
    }

private:
    std::filesystem::path m_path;
};

/// prt-synth's --help text (from PRT_BIN_DIR); fails the test where it cannot run or exits non-zero.
inline std::string synth_help() {
    std::string cmd = "'";  // built by appending: GCC 12 warns (-Wrestrict) on "'" + string
    cmd += (std::filesystem::path(PRT_BIN_DIR) / "prt-synth").string();
    cmd += "' --help";
    std::string help;
    FILE* p = ::popen(cmd.c_str(), "r");
    EXPECT_NE(p, nullptr);
    if (p == nullptr) return help;
    char buf[4096];
    for (std::size_t k; (k = std::fread(buf, 1, sizeof buf, p)) > 0;) help.append(buf, k);
    EXPECT_EQ(::pclose(p), 0);
    return help;
}

/// prt-synth's --help names each of `options` (a missing help text fails too); returns the text.
inline std::string expect_help_names(std::initializer_list<const char*> options) {
    const std::string help = synth_help();
    EXPECT_FALSE(help.empty());
    for (const char* option : options) EXPECT_NE(help.find(option), std::string::npos) << option;
    return help;
}

}  // namespace prt::synth_test
