// PCD through PCL: ascii and binary written by hand here, binary_compressed written by PCL; NaN
// entries of organized clouds dropped and counted; packed rgb; lying headers fail with one line.
#include <cmath>
#include <limits>

#include "import_test_util.h"
#include "pcd_writer_pcl.h"
#include "pcl_backend.h"

namespace {

using namespace prt_import_test;
using prt::pre::import::Report;

class PcdTest : public OptionalReaderTest {
protected:
    PcdTest() : OptionalReaderTest(prt::pre::import::have_pcl(), "PCL") {}
};

std::string pcd_header(const std::string& fields, const std::string& size, const std::string& type,
                       const std::string& count, int width, int height, const std::string& data,
                       const std::string& viewpoint = "0 0 0 1 0 0 0") {
    return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " + size +
           "\nTYPE " + type + "\nCOUNT " + count + "\nWIDTH " + std::to_string(width) + "\nHEIGHT " +
           std::to_string(height) + "\nVIEWPOINT " + viewpoint + "\nPOINTS " +
           std::to_string(width * height) + "\nDATA " + data + "\n";
}

TEST_F(PcdTest, AsciiOrganizedWithNansAndPackedColor) {
    // rgba packed as 0xAARRGGBB in a uint32 field.
    const std::uint32_t c0 = 0x80FF8040u, c1 = 0xFF010203u;
    const std::string text = pcd_header("x y z rgba", "4 4 4 4", "F F F U", "1 1 1 1", 3, 2, "ascii") +
                             "1 2 3 " + std::to_string(c0) + "\n" +
                             "nan nan nan 0\n"
                             "4.5 5.5 6.5 " +
                             std::to_string(c1) + "\n" +
                             "nan nan nan 0\n"
                             "nan nan nan 0\n"
                             "-1 -2 -3 0\n";
    const auto file = write("organized.pcd", text);
    Report report;
    const auto cloud = import(file, report, [] {
        prt::pre::import::Options o;
        o.normals = prt::pre::import::NormalsMode::keep;
        return o;
    }());
    EXPECT_EQ(report.records, 6u);
    EXPECT_EQ(report.nan_entries, 3u);
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_EQ(cloud.positions[0], (std::array<double, 3>{1, 2, 3}));
    EXPECT_EQ(cloud.positions[1], (std::array<double, 3>{4.5, 5.5, 6.5}));
    ASSERT_TRUE(cloud.has_colors());
    EXPECT_EQ(rgba(cloud.colors[0]), (std::array<int, 4>{0xFF, 0x80, 0x40, 0x80}));
    EXPECT_EQ(cloud.colors[1].r, 1);
    EXPECT_EQ(cloud.colors[1].b, 3);
    EXPECT_FALSE(cloud.has_normals());  // --normals keep: none estimated
    EXPECT_NE(report.reader.find("organized 3x2"), std::string::npos) << report.reader;
    const auto lines = report.summary_lines();
    bool counted = false;
    for (const auto& l : lines) counted |= l.find("dropped 3 entries with NaN") != std::string::npos;
    EXPECT_TRUE(counted);
}

TEST_F(PcdTest, BinaryWithNormalsAndRgbFloat) {
    std::string bytes = pcd_header("x y z normal_x normal_y normal_z rgb curvature", "4 4 4 4 4 4 4 4",
                                   "F F F F F F F F", "1 1 1 1 1 1 1 1", 2, 1, "binary");
    auto point = [&](float x, float y, float z, float nx, float ny, float nz, std::uint32_t rgb) {
        for (float f : {x, y, z, nx, ny, nz}) put<float>(bytes, f);
        float packed;
        std::memcpy(&packed, &rgb, 4);
        put<float>(bytes, packed);
        put<float>(bytes, 0.5f);
    };
    point(1, 1, 1, 0, 0, 3, 0x00102030u);
    point(2, 2, 2, 1, 0, 0, 0x00FFFFFFu);
    const auto file = write("binary.pcd", bytes);
    Report report;
    const auto cloud = import(file, report);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_FLOAT_EQ(cloud.normals[0].z, 1.f);
    EXPECT_EQ(rgba(cloud.colors[0]), (std::array<int, 4>{0x10, 0x20, 0x30, 255}));
    EXPECT_TRUE(report.normals_from_file);
    EXPECT_TRUE(has_note(report, "skipped PCD fields: curvature"));
}

TEST_F(PcdTest, BinaryCompressedWrittenByPcl) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<PcdPoint> pts = {{0, 0, 1, 10, 20, 30}, {nan, nan, nan, 0, 0, 0}, {1, 0, 1, 40, 50, 60},
                                 {0, 1, 1, 70, 80, 90}, {nan, nan, nan, 0, 0, 0}, {1, 1, 1, 1, 2, 3}};
    const auto file = path("compressed.pcd");
    write_compressed_pcd(file.string(), pts, 3, 2);
    Report report;
    prt::pre::import::Options keep;
    keep.normals = prt::pre::import::NormalsMode::keep;
    const auto cloud = import(file, report, keep);
    EXPECT_NE(report.reader.find("binary_compressed"), std::string::npos) << report.reader;
    EXPECT_EQ(report.nan_entries, 2u);
    ASSERT_EQ(cloud.size(), 4u);
    EXPECT_EQ(cloud.positions[1], (std::array<double, 3>{1, 0, 1}));
    EXPECT_EQ(cloud.colors[1].r, 40);
    EXPECT_EQ(cloud.colors[3].b, 3);

    // The same file cut short: our check stops it before PCL reads past the end.
    std::ifstream in(file, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto cut = write("cut.pcd", bytes.substr(0, bytes.size() - 5));
    Report report2;
    const std::string msg = error_of([&] { import(cut, report2, keep); });
    EXPECT_NE(msg.find("cut.pcd: binary_compressed data is truncated"), std::string::npos) << msg;
}

// VIEWPOINT tx ty tz qw qx qy qz: PCL's sensor origin, the point estimated normals face.
TEST_F(PcdTest, ViewpointIsTheSensorNormalsFaceIt) {
    std::string text;
    for (int i = 0; i < 30; ++i)
        for (int j = 0; j < 30; ++j) {
            // a gently curved sheet at z ~ 10, above the sensor
            const double x = i * 0.1, y = j * 0.1;
            char buf[96];
            std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", x, y, 10 + 0.05 * std::sin(x) * std::cos(y));
            text += buf;
        }
    // The quaternion written with 6 digits (norm 1 within 1e-6): accepted and normalised.
    const auto file = write("view.pcd", pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 900, 1, "ascii",
                                                   "1.5 1.5 3 0.707107 0 0.707107 0") +
                                            text);
    Report report;
    const auto cloud = import(file, report);
    ASSERT_EQ(cloud.sensors.size(), 1u);
    EXPECT_EQ(cloud.sensors[0].kind, prt::pool::k_sensor_point);
    EXPECT_EQ(cloud.sensors[0].position[0], 1.5);
    EXPECT_EQ(cloud.sensors[0].position[2], 3.0);
    EXPECT_TRUE(report.oriented_to_sensor);
    ASSERT_EQ(cloud.size(), 900u);
    for (const auto& n : cloud.normals) EXPECT_LT(n.z, -0.9f);  // toward the sensor below
    EXPECT_NE(report.sensors_detail.find("PCD VIEWPOINT"), std::string::npos) << report.sensors_detail;

    // --no-sensor: propagation, seeded +z: the opposite orientation, no sensors recorded.
    prt::pre::import::Options none;
    none.no_sensor = true;
    Report r2;
    const auto up = import(file, r2, none);
    EXPECT_TRUE(up.sensors.empty());
    for (const auto& n : up.normals) EXPECT_GT(n.z, 0.9f);
}

TEST_F(PcdTest, IntensityOfAnyTypeAndRgba) {
    struct Case {
        const char* size;
        const char* type;
        const char* v0;
        float f0;
    };
    const Case cases[] = {{"1", "U", "250", 250.f},
                          {"2", "I", "-300", -300.f},
                          {"4", "F", "0.125", 0.125f},
                          {"8", "F", "1e10", 1e10f},
                          {"4", "U", "4000000000", 4e9f}};
    for (const Case& c : cases) {
        const std::string text =
            pcd_header("x y z intensity rgba", std::string("4 4 4 ") + c.size + " 4",
                       std::string("F F F ") + c.type + " U", "1 1 1 1 1", 2, 1, "ascii") +
            "1 2 3 " + c.v0 + " " + std::to_string(0x11223344u) + "\n4 5 6 0 0\n";
        const auto file = write("intensity.pcd", text);
        Report report;
        prt::pre::import::Options keep;
        keep.normals = prt::pre::import::NormalsMode::keep;
        const auto cloud = import(file, report, keep);
        ASSERT_EQ(cloud.size(), 2u);
        ASSERT_TRUE(cloud.has_intensities()) << c.type << c.size;
        EXPECT_EQ(cloud.intensities[0], c.f0) << c.type << c.size;
        EXPECT_EQ(cloud.intensities[1], 0.f);
        ASSERT_TRUE(cloud.has_colors());
        EXPECT_EQ(cloud.colors[0].a, 0x11);
        EXPECT_EQ(cloud.colors[0].r, 0x22);
        EXPECT_EQ(cloud.colors[0].g, 0x33);
        EXPECT_EQ(cloud.colors[0].b, 0x44);
    }
}

TEST_F(PcdTest, MalformedViewpointAndColourFieldsFailWithOneLine) {
    // One ascii point whose header's VIEWPOINT line is `vp`.
    auto viewpoint = [](const char* vp) {
        return pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, 1, "ascii", vp) + "1 2 3\n";
    };
    const BadFile cases[] = {
        {"six.pcd", viewpoint("0 0 0 1 0 0"), "VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz), got 6"},
        {"eight.pcd", viewpoint("0 0 0 1 0 0 0 0"), "VIEWPOINT needs 7 numbers"},
        {"nan.pcd", viewpoint("0 nan 0 1 0 0 0"), "VIEWPOINT value 'nan' is not a finite number"},
        {"inf.pcd", viewpoint("0 0 0 inf 0 0 0"), "VIEWPOINT value 'inf' is not a finite number"},
        {"word.pcd", viewpoint("0 0 0 one 0 0 0"), "VIEWPOINT value 'one' is not a finite number"},
        {"scaled.pcd", viewpoint("0 0 0 2 0 0 0"), "VIEWPOINT quaternion (qw qx qy qz) has norm 2, not 1"},
        {"zero.pcd", viewpoint("0 0 0 0 0 0 0"), "has norm 0, not 1"},
        {"rgb2.pcd", pcd_header("x y z rgb", "4 4 4 2", "F F F U", "1 1 1 1", 1, 1, "ascii") + "1 2 3 7\n",
         "PCD field rgb has SIZE 2 and COUNT 1; a packed colour is one 4-byte value"},
        {"rgba8.pcd", pcd_header("x y z rgba", "4 4 4 8", "F F F F", "1 1 1 1", 1, 1, "ascii") + "1 2 3 7\n",
         "PCD field rgba has SIZE 8"},
        {"rgb3.pcd",
         pcd_header("x y z rgb", "4 4 4 4", "F F F U", "1 1 1 3", 1, 1, "ascii") + "1 2 3 7 8 9\n",
         "PCD field rgb has SIZE 4 and COUNT 3"},
        {"int3.pcd",
         pcd_header("x y z intensity", "4 4 4 4", "F F F F", "1 1 1 3", 1, 1, "ascii") + "1 2 3 7 8 9\n",
         "PCD field intensity has COUNT 3"},
    };
    expect_one_line_errors(cases);
}

TEST_F(PcdTest, BadFilesFailWithOneLine) {
    std::string lying = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 10, 1, "binary");
    for (int i = 0; i < 6; ++i) put<float>(lying, 1.0f * i);  // 2 points of the 10 declared
    const BadFile cases[] = {
        {"empty.pcd", "", "file is empty"},
        {"garbage.pcd", "\x01\x02garbage that is no PCD header\n", "not a valid PCD file"},
        {"lying.pcd", lying, "header declares 10 points but the data ends after 2"},
        {"noxyz.pcd", pcd_header("a b", "4 4", "F F", "1 1", 1, 1, "ascii") + "1 2\n", "no x, y and z"},
        {"sizes.pcd", pcd_header("x y z", "4 4", "F F F", "1 1 1", 1, 1, "ascii") + "1 2 3\n",
         "FIELDS, SIZE, TYPE and COUNT list 3, 2, 3 and 3 entries"},
        {"short_ascii.pcd", pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 3, 1, "ascii") + "1 2 3\n",
         "header declares 3 points but the data has 1 lines"},
        {"nodata.pcd", "VERSION 0.7\nFIELDS x y z\n", "no DATA line"},
    };
    expect_one_line_errors(cases);
}

}  // namespace
