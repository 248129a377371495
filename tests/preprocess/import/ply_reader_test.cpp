// PLY reader: ASCII / binary little / big endian fixtures built byte by byte here, read back to the
// values written (double coordinates, uchar and float colors, radius), with unknown properties,
// other elements and list properties skipped; and every bad-input case.
#include "ply_reader.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "import_test_util.h"

namespace {

using namespace prt_import_test;
using prt::pre::import::Options;
using prt::pre::import::Report;

/// One property value of a fixture row: a scalar, or a list (count type + item type).
struct Item {
    std::string type;
    std::vector<double> values;  // one value for scalars
    std::string count_type;      // non-empty for lists
};

Item scalar(const std::string& type, double v) {
    return {type, {v}, ""};
}
Item list(const std::string& count_type, const std::string& type, std::vector<double> v) {
    return {type, std::move(v), count_type};
}

enum class Enc { ascii, le, be };
const char* enc_name(Enc e) {
    return e == Enc::ascii ? "ascii" : e == Enc::le ? "binary_little_endian" : "binary_big_endian";
}

void put_value(std::string& out, const std::string& type, double v, Enc enc) {
    if (enc == Enc::ascii) {
        char buf[64];
        if (std::isnan(v))
            std::snprintf(buf, sizeof buf, "nan ");
        else if (std::isinf(v))
            std::snprintf(buf, sizeof buf, v > 0 ? "inf " : "-inf ");
        else if (type == "float" || type == "double")
            std::snprintf(buf, sizeof buf, "%.17g ", v);
        else
            std::snprintf(buf, sizeof buf, "%lld ", static_cast<long long>(v));
        out += buf;
        return;
    }
    const bool be = enc == Enc::be;
    if (type == "char")
        put<std::int8_t>(out, static_cast<std::int8_t>(v), be);
    else if (type == "uchar")
        put<std::uint8_t>(out, static_cast<std::uint8_t>(v), be);
    else if (type == "short")
        put<std::int16_t>(out, static_cast<std::int16_t>(v), be);
    else if (type == "ushort")
        put<std::uint16_t>(out, static_cast<std::uint16_t>(v), be);
    else if (type == "int")
        put<std::int32_t>(out, static_cast<std::int32_t>(v), be);
    else if (type == "uint")
        put<std::uint32_t>(out, static_cast<std::uint32_t>(v), be);
    else if (type == "float")
        put<float>(out, static_cast<float>(v), be);
    else if (type == "double")
        put<double>(out, v, be);
    else
        ADD_FAILURE() << "bad fixture type " << type;
}

/// A PLY file: `header_body` is everything between the format line and end_header.
std::string make_ply(Enc enc, const std::string& header_body, const std::vector<std::vector<Item>>& rows) {
    std::string out = std::string("ply\nformat ") + enc_name(enc) +
                      " 1.0\ncomment made by ply_reader_test\n" + header_body + "end_header\n";
    for (const auto& row : rows) {
        for (const Item& item : row) {
            if (!item.count_type.empty())
                put_value(out, item.count_type, static_cast<double>(item.values.size()), enc);
            for (double v : item.values) put_value(out, item.type, v, enc);
        }
        if (enc == Enc::ascii) out += "\n";
    }
    return out;
}

class PlyTest : public TempDirTest, public ::testing::WithParamInterface<Enc> {};

// Intensity under each name real exporters use, in any numeric type, kept as the file holds it;
// the camera element (before or after the vertices) is the scanner.
TEST_P(PlyTest, IntensityNamesAndTypesAndCameraSensor) {
    struct Case {
        const char* name;
        const char* type;
        double value;
    };
    const Case cases[] = {
        {"intensity", "uchar", 200},      {"intensity", "ushort", 40000}, {"scalar_Intensity", "float", 0.25},
        {"reflectance", "double", -12.5}, {"Intensity", "int", -3},       {"scalar_intensity", "char", -7}};
    for (const Case& c : cases) {
        const std::string header =
            "element camera 1\nproperty float view_px\nproperty float view_py\n"
            "property list uchar int junk\nproperty double view_pz\nproperty int viewportx\n"
            "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
            "property " +
            std::string(c.type) + " " + c.name + "\n";
        const std::vector<std::vector<Item>> rows = {
            {scalar("float", 1.5), scalar("float", -2), list("uchar", "int", {4, 5}),
             scalar("double", 1e6 + 0.25), scalar("int", 640)},
            {scalar("float", 1), scalar("float", 2), scalar("float", 3), scalar(c.type, c.value)},
            {scalar("float", 4), scalar("float", 5), scalar("float", 6), scalar(c.type, 0)}};
        const auto file = write("intensity.ply", make_ply(GetParam(), header, rows));
        Report report;
        const auto cloud = prt::pre::import::read_ply(file, report, true);
        ASSERT_EQ(cloud.size(), 2u) << c.name;
        ASSERT_TRUE(cloud.has_intensities()) << c.name << " " << c.type;
        EXPECT_EQ(cloud.intensities[0], static_cast<float>(c.value)) << c.name << " " << c.type;
        EXPECT_EQ(cloud.intensities[1], 0.f);
        ASSERT_EQ(cloud.sensors.size(), 1u);
        EXPECT_EQ(cloud.sensors[0].kind, prt::pool::k_sensor_point);
        EXPECT_EQ(cloud.sensors[0].position[0], 1.5);
        EXPECT_EQ(cloud.sensors[0].position[1], -2.0);
        EXPECT_EQ(cloud.sensors[0].position[2], 1e6 + 0.25);
        EXPECT_FALSE(has_note(report, "skipped elements: camera"));
    }
}

// Colour values outside their type's range, and colours as lists, are errors naming the vertex.
TEST_P(PlyTest, ColoursOfTheWrongTypeFail) {
    struct Case {
        const char* type;
        double value;
        const char* expect;
    };
    const Case cases[] = {{"float", 1.5, "vertex 1: green = 1.5 is outside 0..1"},
                          {"float", -0.25, "vertex 1: green = -0.25 is outside 0..1"},
                          {"double", std::nan(""), "vertex 1: green = nan is outside 0..1"},
                          {"int", 300, "vertex 1: green = 300 is outside 0..255"},
                          {"char", -5, "vertex 1: green = -5 is outside 0..255"}};
    for (const Case& c : cases) {
        const std::string header =
            std::string("element vertex 2\nproperty float x\nproperty float y\nproperty float z\n") +
            "property " + c.type + " red\nproperty " + c.type + " green\nproperty " + c.type + " blue\n";
        const std::vector<std::vector<Item>> rows = {
            {scalar("float", 1), scalar("float", 2), scalar("float", 3), scalar(c.type, 0), scalar(c.type, 0),
             scalar(c.type, 0)},
            {scalar("float", 4), scalar("float", 5), scalar("float", 6), scalar(c.type, 0),
             scalar(c.type, c.value), scalar(c.type, 0)}};
        const auto file = write("badcolour.ply", make_ply(GetParam(), header, rows));
        Report report;
        const std::string msg = error_of([&] { prt::pre::import::read_ply(file, report, true); });
        EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
        EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos);
    }
    const auto list_file = write(
        "listcolour.ply",
        make_ply(
            GetParam(),
            "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty list uchar "
            "uchar red\nproperty uchar green\nproperty uchar blue\n",
            {{scalar("float", 1), scalar("float", 2), scalar("float", 3), list("uchar", "uchar", {1, 2}),
              scalar("uchar", 3), scalar("uchar", 4)}}));
    Report report;
    const std::string msg = error_of([&] { prt::pre::import::read_ply(list_file, report, true); });
    EXPECT_EQ(msg.rfind(list_file.string() + ": vertex property 'red' is a list", 0), 0u) << msg;
}

// Known values: doubles chosen so float rounding would show (1e6 + 0.125, 0.1, 0.2).
TEST_P(PlyTest, RoundTripKnownValues) {
    const std::string header =
        "element camera 1\nproperty float fov\n"
        "element vertex 3\n"
        "property double x\nproperty double y\nproperty double z\nproperty float confidence\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float radius\n"
        "element face 2\nproperty list uchar int vertex_indices\n"
        "element range_grid 4\nproperty list uchar int vertex_indices\n";
    auto v = [](double x, double y, double z, double c, double nx, double ny, double nz, int r, int g, int b,
                double rad) {
        return std::vector<Item>{scalar("double", x), scalar("double", y), scalar("double", z),
                                 scalar("float", c),  scalar("float", nx), scalar("float", ny),
                                 scalar("float", nz), scalar("uchar", r),  scalar("uchar", g),
                                 scalar("uchar", b),  scalar("float", rad)};
    };
    std::vector<std::vector<Item>> rows = {{scalar("float", 60.0)},
                                           v(1.5, -2.25, 1e6 + 0.125, 0.7, 0, 0, 2, 10, 20, 30, 0.5),
                                           v(0.1, 0.2, 0.3, 0.9, 1, 0, 0, 255, 0, 128, 0.25),
                                           v(-1, -1, -1, 0.1, 0, -3, 4, 0, 0, 0, 1.0),
                                           {list("uchar", "int", {0, 1, 2})},
                                           {list("uchar", "int", {2, 1, 0})},
                                           {list("uchar", "int", {})},
                                           {list("uchar", "int", {7})},
                                           {list("uchar", "int", {1, 2})},
                                           {list("uchar", "int", {})}};
    const auto file = write("model.ply", make_ply(GetParam(), header, rows));
    Report report;
    const auto cloud = import(file, report);
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_EQ(cloud.positions[0], (std::array<double, 3>{1.5, -2.25, 1e6 + 0.125}));
    EXPECT_EQ(cloud.positions[1], (std::array<double, 3>{0.1, 0.2, 0.3}));  // exact: read as double
    EXPECT_EQ(cloud.positions[2], (std::array<double, 3>{-1, -1, -1}));
    ASSERT_TRUE(cloud.has_normals());
    EXPECT_FLOAT_EQ(cloud.normals[0].z, 1.f);  // (0,0,2) renormalised
    EXPECT_FLOAT_EQ(cloud.normals[1].x, 1.f);
    EXPECT_FLOAT_EQ(cloud.normals[2].y, -0.6f);
    EXPECT_FLOAT_EQ(cloud.normals[2].z, 0.8f);
    ASSERT_TRUE(cloud.has_colors());
    EXPECT_EQ(rgba(cloud.colors[0]), (std::array<int, 4>{10, 20, 30, 255}));
    EXPECT_EQ(cloud.colors[1].r, 255);
    EXPECT_EQ(cloud.colors[1].b, 128);
    ASSERT_TRUE(cloud.has_radii());
    EXPECT_FLOAT_EQ(cloud.radii[0], 0.5f);
    EXPECT_FLOAT_EQ(cloud.radii[1], 0.25f);
    EXPECT_FLOAT_EQ(cloud.radii[2], 1.0f);
    EXPECT_FALSE(cloud.flags & prt::pool::k_model_normals_estimated);
    EXPECT_NE(report.reader.find(enc_name(GetParam())), std::string::npos) << report.reader;
    EXPECT_TRUE(has_note(report, "skipped vertex properties: confidence"));
    EXPECT_TRUE(has_note(report, "skipped elements: camera (1 rows), face (2 rows), range_grid (4 rows)"));
    EXPECT_TRUE(report.normals_from_file);
    EXPECT_EQ(report.clean.kept, 3u);
}

// Float colors 0..1, float coordinates, and a list property inside the vertex element (rows of
// varying size), plus an int16 coordinate type.
TEST_P(PlyTest, FloatColorsAndListInVertex) {
    const std::string header =
        "element vertex 3\n"
        "property float x\nproperty list uchar float texcoords\nproperty short y\nproperty float z\n"
        "property float red\nproperty float green\nproperty float blue\n";
    std::vector<std::vector<Item>> rows = {
        {scalar("float", 0.5), list("uchar", "float", {1, 2, 3}), scalar("short", -7), scalar("float", 2),
         scalar("float", 0), scalar("float", 0.5), scalar("float", 1)},
        {scalar("float", 1.5), list("uchar", "float", {}), scalar("short", 300), scalar("float", 3),
         scalar("float", 1), scalar("float", 1), scalar("float", 1)},
        {scalar("float", -4), list("uchar", "float", {9}), scalar("short", 0), scalar("float", 1),
         scalar("float", 0.2), scalar("float", 1.0), scalar("float", 0.0)}};
    const auto file = write("colors.ply", make_ply(GetParam(), header, rows));
    Report report;
    prt::pre::PointCloud cloud = prt::pre::import::read_ply(file, report, true);
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_EQ(cloud.positions[0], (std::array<double, 3>{0.5, -7, 2}));
    EXPECT_EQ(cloud.positions[1], (std::array<double, 3>{1.5, 300, 3}));
    EXPECT_EQ(cloud.positions[2], (std::array<double, 3>{-4, 0, 1}));
    ASSERT_TRUE(cloud.has_colors());
    EXPECT_EQ(cloud.colors[0].r, 0);
    EXPECT_EQ(cloud.colors[0].g, 128);  // 0.5 * 255 = 127.5 rounds to 128
    EXPECT_EQ(cloud.colors[0].b, 255);
    EXPECT_EQ(cloud.colors[2].r, 51);  // 0.2 * 255
    EXPECT_EQ(cloud.colors[2].g, 255);
    EXPECT_EQ(cloud.colors[2].b, 0);
    EXPECT_FALSE(cloud.has_normals());
    EXPECT_TRUE(has_note(report, "skipped vertex properties: texcoords"));
}

TEST_P(PlyTest, HeaderDeclaringMoreVerticesThanPresentFails) {
    const std::string header = "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n";
    std::vector<std::vector<Item>> rows;
    for (int i = 0; i < 3; ++i) rows.push_back({scalar("float", i), scalar("float", 0), scalar("float", 0)});
    const auto file = write("short.ply", make_ply(GetParam(), header, rows));
    Report report;
    const std::string msg = error_of([&] { import(file, report); });
    EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find("declares 5 vertices"), std::string::npos) << msg;
    EXPECT_NE(msg.find("ends after 3"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line";
}

TEST_P(PlyTest, TruncatedListElementAfterVerticesFails) {
    const std::string header =
        "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 3\nproperty list uchar int vertex_indices\n";
    std::vector<std::vector<Item>> rows = {{scalar("float", 0), scalar("float", 0), scalar("float", 0)},
                                           {list("uchar", "int", {0, 0, 0})}};
    const auto file = write("faces.ply", make_ply(GetParam(), header, rows));
    Report report;
    const std::string msg = error_of([&] { prt::pre::import::read_ply(file, report, true); });
    EXPECT_NE(msg.find("declares 3 'face' rows but the data ends after 1"), std::string::npos) << msg;
}

TEST_P(PlyTest, TrailingDataIsAWarning) {
    const std::string header = "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n";
    std::vector<std::vector<Item>> rows;
    for (int i = 0; i < 3; ++i) rows.push_back({scalar("float", i), scalar("float", 1), scalar("float", 2)});
    const auto file = write("long.ply", make_ply(GetParam(), header, rows));
    Report report;
    const auto cloud = prt::pre::import::read_ply(file, report, true);
    EXPECT_EQ(cloud.size(), 2u);
    EXPECT_TRUE(has_note(report, "after the last declared element"))
        << ::testing::PrintToString(report.notes);
}

// NaN/Inf coordinates, zero and NaN normals, duplicates: dropped and counted, never silent.
TEST_P(PlyTest, BadPointsAreDroppedAndCounted) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    const std::string header =
        "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n";
    auto v = [](double x, double y, double z, double nx, double ny, double nz) {
        return std::vector<Item>{scalar("float", x),  scalar("float", y),  scalar("float", z),
                                 scalar("float", nx), scalar("float", ny), scalar("float", nz)};
    };
    std::vector<std::vector<Item>> rows = {v(0, 0, 0, 0, 0, 1), v(nan, 0, 0, 0, 0, 1), v(1, inf, 0, 0, 0, 1),
                                           v(2, 0, 0, 0, 0, 0), v(3, 0, 0, nan, 0, 1), v(0, 0, 0, 0, 1, 0),
                                           v(4, 4, 4, 1, 0, 0), v(0, 0, 0, 1, 0, 0)};
    const auto file = write("bad.ply", make_ply(GetParam(), header, rows));
    Report report;
    auto cloud = import(file, report);
    EXPECT_EQ(report.clean.input, 8u);
    EXPECT_EQ(report.clean.non_finite, 2u);
    EXPECT_EQ(report.clean.zero_normal, 2u);
    EXPECT_EQ(report.clean.duplicates, 2u);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.normals[0].z, 1.f);  // the first of the duplicates is kept
    EXPECT_NE(report.clean.summary().find("2 duplicates"), std::string::npos);

    Options keep;
    keep.keep_duplicates = true;
    Report report2;
    cloud = import(file, report2, keep);
    EXPECT_EQ(report2.clean.duplicates, 0u);
    EXPECT_EQ(cloud.size(), 4u);
}

INSTANTIATE_TEST_SUITE_P(Encodings, PlyTest, ::testing::Values(Enc::ascii, Enc::le, Enc::be),
                         [](const auto& info) { return std::string(enc_name(info.param)); });

class PlyErrors : public TempDirTest {
protected:
    /// Imports `bytes` as NAME and returns the error, checking it is one line naming the file.
    std::string fail(const std::string& name, const std::string& bytes) {
        const auto file = write(name, bytes);
        Report report;
        const std::string msg = error_of([&] { import(file, report); });
        EXPECT_FALSE(msg.empty()) << name << " should fail";
        EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        return msg;
    }
};

TEST_F(PlyErrors, EmptyFile) {
    EXPECT_NE(fail("empty.ply", "").find("empty"), std::string::npos);
}

TEST_F(PlyErrors, NotPly) {
    EXPECT_NE(fail("text.ply", "hello world\n").find("not a PLY file"), std::string::npos);
    std::string garbage;
    for (int i = 0; i < 4096; ++i) garbage.push_back(static_cast<char>((i * 7919 + 13) & 0xFF));
    EXPECT_NE(fail("garbage.ply", garbage).find("not a PLY file"), std::string::npos);
}

TEST_F(PlyErrors, HeaderProblems) {
    EXPECT_NE(
        fail("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n").find("end_header"),
        std::string::npos);
    EXPECT_NE(
        fail("badfmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n").find("unknown PLY format"),
        std::string::npos);
    EXPECT_NE(fail("badtype.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n1\n")
                  .find("line 4: unknown property type 'quad'"),
              std::string::npos);
    EXPECT_NE(fail("orphan.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n")
                  .find("before any element"),
              std::string::npos);
    EXPECT_NE(fail("noformat.ply", "ply\nelement vertex 0\nend_header\n").find("no format line"),
              std::string::npos);
    EXPECT_NE(
        fail("novertex.ply", "ply\nformat ascii 1.0\nelement face 0\nend_header\n").find("no vertex element"),
        std::string::npos);
    EXPECT_NE(fail("noz.ply",
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                   "end_header\n1 2\n")
                  .find("no z property"),
              std::string::npos);
    EXPECT_NE(
        fail("count.ply", "ply\nformat ascii 1.0\nelement vertex lots\nend_header\n").find("invalid count"),
        std::string::npos);
    EXPECT_NE(
        fail("keyword.ply", "ply\nformat ascii 1.0\nbanana\nend_header\n").find("unknown PLY header keyword"),
        std::string::npos);
}

TEST_F(PlyErrors, AsciiGarbageNamesTheLine) {
    const std::string msg = fail("words.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty "
                                 "float y\nproperty float z\nend_header\n1 2 3\n4 five 6\n");
    EXPECT_NE(msg.find("line 9: 'five' is not a number (vertex 1, property y)"), std::string::npos) << msg;
}

TEST_F(PlyErrors, NoPointsLeft) {
    const std::string msg =
        fail("allnan.ply",
             "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty "
             "float z\nend_header\nnan 0 0\n0 inf 0\n");
    EXPECT_NE(msg.find("no points left"), std::string::npos) << msg;
    EXPECT_NE(msg.find("2 non-finite"), std::string::npos) << msg;
    EXPECT_NE(fail("zero.ply",
                   "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty "
                   "float z\nend_header\n")
                  .find("no points left"),
              std::string::npos);
}

TEST_F(PlyErrors, IncompleteNormalsAndColorsAreReportedAndIgnored) {
    const auto file = write("partial.ply",
                            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                            "property float z\nproperty float nx\nproperty uchar red\nend_header\n"
                            "1 2 3 1 200\n");
    Report report;
    const auto cloud = prt::pre::import::read_ply(file, report, true);
    EXPECT_FALSE(cloud.has_normals());
    EXPECT_FALSE(cloud.has_colors());
    EXPECT_TRUE(has_note(report, "normals incomplete"));
    EXPECT_TRUE(has_note(report, "colors incomplete"));
    EXPECT_TRUE(has_note(report, "skipped vertex properties: nx, red"));
}

TEST_F(PlyErrors, CrLfHeaderAndAlphaAndDoubleRadius) {
    const auto file = write("crlf.ply",
                            "ply\r\nformat ascii 1.0\r\nelement vertex 1\r\nproperty float x\r\nproperty "
                            "float y\r\nproperty float z\r\nproperty uchar red\r\nproperty uchar green\r\n"
                            "property uchar blue\r\nproperty uchar alpha\r\nproperty double radius\r\n"
                            "end_header\r\n1 2 3 4 5 6 7 0.125\r\n");
    Report report;
    const auto cloud = prt::pre::import::read_ply(file, report, true);
    ASSERT_EQ(cloud.size(), 1u);
    EXPECT_EQ(cloud.positions[0], (std::array<double, 3>{1, 2, 3}));
    EXPECT_EQ(cloud.colors[0].a, 7);
    EXPECT_FLOAT_EQ(cloud.radii[0], 0.125f);
}

}  // namespace
