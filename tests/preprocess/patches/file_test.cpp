// Patch file readers: the .bpt and Newell formats, format detection, and one-line
// "FILE:LINE: problem" errors for every kind of bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "patch_file.h"
#include "prt/error.h"

namespace {

using prt::patches::parse_patches;
using prt::patches::PatchFormat;

/// Two patches sharing an edge in Newell form (vertices 1..28; patch 2 reuses patch 1's last column).
std::string newell_text() {
    std::string s = "2\n";
    s += "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n";
    s += "4,17,18,19,8,20,21,22,12,23,24,25,16,26,27,28\n";
    s += "28\n";
    for (int v = 1; v <= 28; ++v)
        s += std::to_string(v) + "," + std::to_string(v * 0.5) + ",-" + std::to_string(v) + "e-1\n";
    return s;
}

/// The same two patches in .bpt form.
std::string bpt_text() {
    const int idx[2][16] = {{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16},
                            {4, 17, 18, 19, 8, 20, 21, 22, 12, 23, 24, 25, 16, 26, 27, 28}};
    std::string s = "2\n";
    for (const auto& patch : idx) {
        s += "3 3\n";
        for (int v : patch)
            s += std::to_string(v) + " " + std::to_string(v * 0.5) + " -" + std::to_string(v) + "e-1\n";
    }
    return s;
}

/// `text` with its line `line` (1-based) replaced by `replacement`.
std::string replace_line(std::string text, int line, const std::string& replacement) {
    std::size_t pos = 0;
    for (int l = 1; l < line; ++l) pos = text.find('\n', pos) + 1;
    const std::size_t end = text.find('\n', pos);
    return text.replace(pos, end - pos, replacement);
}

std::string error_of(const std::string& text, PatchFormat format = PatchFormat::automatic) {
    try {
        parse_patches(text, "f.txt", format);
    } catch (const prt::Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        return m;
    }
    return "";
}

TEST(PatchFile, NewellAndBptGiveTheSameNets) {
    const auto a = parse_patches(newell_text(), "a", PatchFormat::automatic);
    const auto b = parse_patches(bpt_text(), "b", PatchFormat::automatic);
    EXPECT_EQ(a.format, PatchFormat::newell);
    EXPECT_EQ(b.format, PatchFormat::bpt);
    ASSERT_EQ(a.nets.size(), 2u);
    ASSERT_EQ(b.nets.size(), 2u);
    for (int p = 0; p < 2; ++p)
        for (int k = 0; k < 16; ++k) {
            EXPECT_EQ(a.nets[p].p[k].x, b.nets[p].p[k].x);
            EXPECT_EQ(a.nets[p].p[k].y, b.nets[p].p[k].y);
            EXPECT_EQ(a.nets[p].p[k].z, b.nets[p].p[k].z);
        }
    // 1-based indices, row-major nets: patch 2's first point is vertex 4 = (4, 2, -0.4)
    EXPECT_EQ(a.nets[1].p[0].x, 4.0);
    EXPECT_EQ(a.nets[1].p[0].y, 2.0);
    EXPECT_DOUBLE_EQ(a.nets[1].p[0].z, -0.4);
    EXPECT_EQ(a.nets[1].p[15].x, 28.0);
}

TEST(PatchFile, ToleratesCrlfBlankLinesAndSpacesAroundCommas) {
    std::string t = newell_text();
    std::string crlf;
    for (char c : t) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    crlf = "\r\n" + crlf + "\r\n\r\n";
    EXPECT_EQ(parse_patches(crlf, "x", PatchFormat::automatic).nets.size(), 2u);
    std::string spaced = t;
    for (std::size_t i = 0; (i = spaced.find(',', i)) != std::string::npos; i += 3)
        spaced.replace(i, 1, " , ");
    EXPECT_EQ(parse_patches(spaced, "x", PatchFormat::newell).nets.size(), 2u);
}

TEST(PatchFile, SharedTeapotFilesAgree) {
    const std::string dir = std::string(PRT_SHARED_DATA_DIR) + "/bezier";
    if (!std::filesystem::exists(dir + "/teapot") || !std::filesystem::exists(dir + "/teapot.bpt"))
        GTEST_SKIP() << "shared data not found: " << dir
                     << " (../shared/data/bezier is absent on this machine)";
    const auto a = prt::patches::read_patch_file(dir + "/teapot", PatchFormat::automatic);
    const auto b = prt::patches::read_patch_file(dir + "/teapot.bpt", PatchFormat::automatic);
    EXPECT_EQ(a.format, PatchFormat::newell);
    EXPECT_EQ(b.format, PatchFormat::bpt);
    ASSERT_EQ(a.nets.size(), 32u);
    ASSERT_EQ(b.nets.size(), 32u);
    for (int p = 0; p < 32; ++p)
        for (int k = 0; k < 16; ++k) {
            EXPECT_EQ(a.nets[p].p[k].x, b.nets[p].p[k].x) << p << " " << k;
            EXPECT_EQ(a.nets[p].p[k].y, b.nets[p].p[k].y);
            EXPECT_EQ(a.nets[p].p[k].z, b.nets[p].p[k].z);
        }
    for (const char* name : {"teacup", "teaspoon", "bigguy"}) {
        const auto s = prt::patches::read_patch_file(dir + "/" + name, PatchFormat::automatic);
        EXPECT_GT(s.nets.size(), 10u) << name;
    }
}

TEST(PatchFile, NewellErrorsNameFileAndLine) {
    const std::string good = newell_text();
    auto with_line = [&](int line, const std::string& replacement) {
        return replace_line(good, line, replacement);
    };
    EXPECT_EQ(error_of(good), "");
    EXPECT_EQ(error_of(with_line(2, "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15")),
              "f.txt:2: patch 1: expected 16 vertex indices, got 15");
    EXPECT_EQ(error_of(with_line(3, "4,17,18,19,8,20,21,22,12,23,24,25,16,26,27,29")),
              "f.txt:3: patch 2: vertex index 29 out of range 1..28");
    EXPECT_EQ(error_of(with_line(3, "0,17,18,19,8,20,21,22,12,23,24,25,16,26,27,28")),
              "f.txt:3: patch 2: vertex index 0 (indices are 1-based)");
    EXPECT_EQ(error_of(with_line(2, "1,2,x3,4,5,6,7,8,9,10,11,12,13,14,15,16")),
              "f.txt:2: patch 1 vertex index: 'x3' is not a whole number");
    EXPECT_EQ(error_of(with_line(2, "1,2,,4,5,6,7,8,9,10,11,12,13,14,15,16")),
              "f.txt:2: empty field between commas");
    EXPECT_EQ(error_of(with_line(8, "7,nan,3")), "f.txt:8: vertex 4: 'nan' is not a finite number");
    EXPECT_EQ(error_of(with_line(9, "7,1e999,3")), "f.txt:9: vertex 5: '1e999' is not a finite number");
    EXPECT_EQ(error_of(with_line(10, "7,1.5.2,3")), "f.txt:10: vertex 6: '1.5.2' is not a number");
    EXPECT_EQ(error_of(with_line(11, "7,1")),
              "f.txt:11: vertex 7: expected 3 coordinates x y z, got 2 fields");
    EXPECT_EQ(error_of(with_line(4, "29")),
              "f.txt:32: unexpected end of file after 28 of the 29 vertices the header announces");
    EXPECT_EQ(
        error_of(with_line(4, "27")),
        "f.txt:32: unexpected content after the last vertex (the header says 27): '28,14.000000,-28e-1'");
    EXPECT_EQ(error_of(with_line(1, "3")), "f.txt:4: patch 3: expected 16 vertex indices, got 1");
    EXPECT_EQ(error_of(with_line(1, "0")), "f.txt:1: the patch count is 0");
    EXPECT_EQ(error_of(with_line(1, "-2")), "f.txt:1: the patch count: '-2' is not a whole number");
    // a huge count is refused before anything is allocated
    EXPECT_EQ(error_of(with_line(1, "4000000000")),
              "f.txt:1: the patch count 4000000000 exceeds the limit of 4194304");
    EXPECT_EQ(error_of(with_line(1, "3000000")), "f.txt:4: patch 3: expected 16 vertex indices, got 1");
    EXPECT_EQ(error_of("2\n1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n"),
              "f.txt:2: unexpected end of file after 1 of the 2 patches the header announces");
    EXPECT_EQ(error_of(""), "f.txt:1: unexpected end of file (empty file): expected the patch count");
    EXPECT_EQ(error_of("\n\n  \n"), "f.txt:3: unexpected end of file (empty file): expected the patch count");
    EXPECT_EQ(error_of(std::string("1\n1,2\0,3\n", 9)),
              "f.txt:2: NUL byte in the line (a binary file, not a patch file)");
}

TEST(PatchFile, BptErrorsNameFileAndLine) {
    const std::string good = bpt_text();
    auto with_line = [&](int line, const std::string& replacement) {
        return replace_line(good, line, replacement);
    };
    EXPECT_EQ(error_of(good), "");
    EXPECT_EQ(error_of(with_line(2, "3 2")),
              "f.txt:2: patch 1: degrees 3 2 are not supported (only bicubic patches, '3 3')");
    EXPECT_EQ(error_of(with_line(19, "3")), "f.txt:19: patch 2: expected the degree line '3 3', got '3'");
    EXPECT_EQ(error_of(with_line(5, "1 2 inf")),
              "f.txt:5: patch 1 control point 3: 'inf' is not a finite number");
    EXPECT_EQ(error_of(with_line(5, "1 2")),
              "f.txt:5: patch 1 control point 3: expected 3 coordinates x y z, got 2 fields");
    EXPECT_EQ(error_of(with_line(1, "3")),
              "f.txt:35: unexpected end of file after 2 of the 3 patches the header announces");
    EXPECT_EQ(error_of(with_line(1, "1")),
              "f.txt:19: unexpected content after the last patch (the header says 1): '3 3'");
    EXPECT_EQ(error_of(good.substr(0, good.find("3 3", 10) + 4) + "1 2 3\n"),
              "f.txt:20: unexpected end of file in patch 2 after 1 of its 16 control points");
    // an explicit format overrides detection
    EXPECT_NE(error_of(good, PatchFormat::newell), "");
}

TEST(PatchFile, MissingFileAndFolder) {
    try {
        prt::patches::read_patch_file("/nonexistent/teapot", PatchFormat::automatic);
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/teapot: cannot open", 0), 0u) << e.what();
    }
    try {
        prt::patches::read_patch_file(std::filesystem::temp_directory_path(), PatchFormat::automatic);
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("is a folder"), std::string::npos) << e.what();
    }
    EXPECT_THROW(prt::patches::parse_patch_format("obj"), prt::Error);
}

}  // namespace
