// XYZ text reader: 3 and 6 columns, spaces/tabs/commas, comments, CRLF; malformed lines counted.
#include "xyz_reader.h"

#include "import_test_util.h"

namespace {

using namespace prt_import_test;
using prt::pre::import::Report;
using XyzTest = TempDirTest;

TEST_F(XyzTest, ThreeColumnsWithCommentsAndCommas) {
    const auto file =
        write("p.xyz", "# a comment line\n1 2 3\n\n4.5,5.5,-6.5   # trailing comment\r\n\t7\t8\t9e-3\n");
    Report report;
    const auto cloud = prt::pre::import::read_xyz(file, report, true);
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_EQ(cloud.positions[0], (std::array<double, 3>{1, 2, 3}));
    EXPECT_EQ(cloud.positions[1], (std::array<double, 3>{4.5, 5.5, -6.5}));
    EXPECT_EQ(cloud.positions[2], (std::array<double, 3>{7, 8, 9e-3}));
    EXPECT_FALSE(cloud.has_normals());
    EXPECT_EQ(report.malformed_lines, 0u);
}

TEST_F(XyzTest, SixColumnsGiveNormals) {
    const auto file = write("n.xyz", "0.1 0.2 0.3 0 0 1\n1, 1, 1, 0, 2, 0\n");
    Report report;
    const auto cloud = import(file, report);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.positions[0], (std::array<double, 3>{0.1, 0.2, 0.3}));
    EXPECT_FLOAT_EQ(cloud.normals[0].z, 1.f);
    EXPECT_FLOAT_EQ(cloud.normals[1].y, 1.f);  // renormalised
    EXPECT_TRUE(report.normals_from_file);
}

TEST_F(XyzTest, MalformedLinesAreDroppedAndCounted) {
    const auto file = write("m.xyz", "1 2 3\n4 5\nfoo bar baz\n6 7 8\n9 10 11 12\n13 14 15\n");
    Report report;
    const auto cloud = prt::pre::import::read_xyz(file, report, true);
    EXPECT_EQ(cloud.size(), 3u);
    EXPECT_EQ(report.malformed_lines, 3u);
    EXPECT_TRUE(has_note(report, "dropped 3 malformed lines (not 3 numbers) (first at line 2: '4 5')"))
        << ::testing::PrintToString(report.notes);
}

TEST_F(XyzTest, NanAndInfAreCountedByClean) {
    const auto file = write("nan.xyz", "1 2 3\nnan 0 0\n0 -inf 0\n1 2 3\n");
    Report report;
    prt::pre::import::Options keep;
    keep.normals = prt::pre::import::NormalsMode::keep;
    const auto cloud = import(file, report, keep);
    EXPECT_EQ(cloud.size(), 1u);
    EXPECT_EQ(report.clean.non_finite, 2u);
    EXPECT_EQ(report.clean.duplicates, 1u);
}

TEST_F(XyzTest, BadFilesFailWithOneLine) {
    std::string binary(64, '\0');
    binary[3] = 'x';
    const BadFile cases[] = {
        {"empty.xyz", "", "file is empty"},
        {"comments.xyz", "# nothing\n\n# here\n", "no points"},
        {"binary.xyz", binary, "binary data"},
        {"words.xyz", "this is not\na point cloud\nat all\n", "no valid"},
        {"mostly.xyz", "1 2 3\nx\ny\nz\n", "not XYZ text: 3 of 4 lines"},
    };
    expect_one_line_errors(cases);
}

TEST_F(XyzTest, MissingFileFails) {
    Report report;
    const std::string msg = error_of([&] { import(path("absent.xyz"), report); });
    EXPECT_NE(msg.find("absent.xyz: cannot open"), std::string::npos) << msg;
}

// --normals keep on a file without normals: no estimation (no PCL needed), no normals written.
TEST_F(XyzTest, KeepWithoutNormalsWritesNone) {
    const auto file = write("bare.xyz", "0 0 0\n1 0 0\n0 1 0\n1 1 0\n");
    prt::pre::import::Options options;
    options.normals = prt::pre::import::NormalsMode::keep;
    Report report;
    const auto cloud = import(file, report, options);
    EXPECT_FALSE(cloud.has_normals());
    EXPECT_NE(report.normals_detail.find("none"), std::string::npos);
}

}  // namespace
