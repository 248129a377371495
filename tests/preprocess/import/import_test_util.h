// Helpers for the prt-import tests: a per-test temporary folder and byte-exact fixture writers.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "import.h"

namespace prt_import_test {

namespace fs = std::filesystem;

/// A file prt-import must refuse: its name, its bytes, and a part of the message expected.
struct BadFile {
    const char* name;
    std::string bytes;
    const char* expect;
};

/// A fresh folder per test, removed afterwards.
class TempDirTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() / ("prt_import_" + std::to_string(::getpid()) + "_" +
                                             info->test_suite_name() + "_" + info->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override { fs::remove_all(m_dir); }

    fs::path path(const std::string& name) const { return m_dir / name; }

    fs::path write(const std::string& name, const std::string& bytes) const {
        const fs::path p = path(name);
        std::ofstream out(p, std::ios::binary);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        return p;
    }

    /// Writes every file and checks that importing it fails with one line, "<path>: ...",
    /// containing its `expect`.
    void expect_one_line_errors(std::span<const BadFile> files) const;

    fs::path m_dir;
};

/// TempDirTest for an optional reader: each test skips where this build lacks it (`available`
/// false; `what` names it in the message).
class OptionalReaderTest : public TempDirTest {
protected:
    OptionalReaderTest(bool available, std::string what) : m_available(available), m_what(std::move(what)) {}
    void SetUp() override {
        TempDirTest::SetUp();
        if (!m_available) GTEST_SKIP() << "this build has no " << m_what;
    }

    bool m_available;
    std::string m_what;
};

/// Points as XYZ text, one "x y z" line each, with every digit a double holds.
inline std::string xyz_text(const std::vector<std::array<double, 3>>& pts) {
    std::string s;
    char buf[128];
    for (const auto& p : pts) {
        std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
        s += buf;
    }
    return s;
}

/// Appends the bytes of a value, little or big endian.
template <class T>
void put(std::string& out, T value, bool big_endian = false) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (big_endian == (std::endian::native == std::endian::little))
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    out.append(reinterpret_cast<const char*>(bytes), sizeof(T));
}

/// Imports with quiet options unless given; the Report comes back through `report`.
inline prt::pre::PointCloud import(const fs::path& p, prt::pre::import::Report& report,
                                   prt::pre::import::Options options = {}) {
    options.quiet = true;
    return prt::pre::import::import_file(p, options, report);
}

/// The message of the prt::Error `fn` throws ("" when it throws none).
template <class Fn>
std::string error_of(Fn&& fn) {
    try {
        fn();
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

inline void TempDirTest::expect_one_line_errors(std::span<const BadFile> files) const {
    for (const BadFile& c : files) {
        const auto file = write(c.name, c.bytes);
        prt::pre::import::Report report;
        const std::string msg = error_of([&] { import(file, report); });
        EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
        EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
}

/// A colour's channels r, g, b, a as one comparable value.
inline std::array<int, 4> rgba(const prt::pool::Rgba8& c) {
    return {c.r, c.g, c.b, c.a};
}

/// Whether any note contains `text`.
inline bool has_note(const prt::pre::import::Report& r, const std::string& text) {
    for (const std::string& n : r.notes)
        if (n.find(text) != std::string::npos) return true;
    return false;
}

}  // namespace prt_import_test
