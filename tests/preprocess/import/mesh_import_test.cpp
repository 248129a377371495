// Meshes through OpenMesh (OBJ, OFF, STL, PLY with faces): area-weighted vertex normals against a
// hand computation, and uniform surface sampling (counts, points on the surface, face normals).
#include <cmath>
#include <cstdio>
#include <map>

#include "import_test_util.h"
#include "mesh.h"

namespace {

using namespace prt_import_test;
using prt::pre::import::Options;
using prt::pre::import::Report;

class MeshTest : public OptionalReaderTest {
protected:
    MeshTest() : OptionalReaderTest(prt::pre::import::have_openmesh(), "OpenMesh") {}
};

// A square pyramid: base corners (+-1, +-1, 0), apex (0, 0, 1); faces wound outward.
//   v0 (1,1,0)  v1 (1,-1,0)  v2 (-1,-1,0)  v3 (-1,1,0)  v4 (0,0,1)
// Twice the area vector of each face (cross products worked by hand):
//   side +x (v1 v0 v4): (2,0,2)   side +y (v0 v3 v4): (0,2,2)
//   side -x (v3 v2 v4): (-2,0,2)  side -y (v2 v1 v4): (0,-2,2)
//   base as one quad (v0 v1 v2 v3): (0,0,-8); triangulated along v0-v2: (v0 v1 v2) and (v0 v2 v3),
//   (0,0,-4) each.
const char* k_pyramid_vertices = "1 1 0\n1 -1 0\n-1 -1 0\n-1 1 0\n0 0 1\n";

void expect_normal(const prt::pool::Float3& n, double x, double y, double z, const char* what) {
    const double len = std::sqrt(x * x + y * y + z * z);
    EXPECT_NEAR(n.x, x / len, 1e-6) << what;
    EXPECT_NEAR(n.y, y / len, 1e-6) << what;
    EXPECT_NEAR(n.z, z / len, 1e-6) << what;
}

/// Triangulated pyramid: sums of the hand-computed area vectors at each vertex.
void expect_triangulated_pyramid(const prt::pre::PointCloud& cloud) {
    ASSERT_EQ(cloud.size(), 5u);
    ASSERT_TRUE(cloud.has_normals());
    // Find each vertex by position (STL merges vertices in its own order).
    auto at = [&](double x, double y, double z) -> const prt::pool::Float3& {
        for (std::size_t i = 0; i < cloud.size(); ++i)
            if (cloud.positions[i] == std::array<double, 3>{x, y, z}) return cloud.normals[i];
        ADD_FAILURE() << "no vertex at " << x << "," << y << "," << z;
        return cloud.normals[0];
    };
    expect_normal(at(1, 1, 0), 2, 2, -4, "v0: +x, +y, both base halves");  // (2,0,2)+(0,2,2)+(0,0,-8)
    expect_normal(at(1, -1, 0), 2, -2, 0, "v1: +x, -y, one base half");    // (2,0,2)+(0,-2,2)+(0,0,-4)
    expect_normal(at(-1, -1, 0), -2, -2, -4, "v2: -x, -y, both base halves");
    expect_normal(at(-1, 1, 0), -2, 2, 0, "v3: +y, -x, one base half");
    expect_normal(at(0, 0, 1), 0, 0, 8, "apex: the four sides");
}

TEST_F(MeshTest, ObjAreaWeightedNormals) {
    const auto file = write(
        "pyramid.obj", std::string("# pyramid\n") + [] {
            std::string v;
            for (const char* p = k_pyramid_vertices; *p;) {
                const char* e = std::strchr(p, '\n');
                v += "v " + std::string(p, e) + "\n";
                p = e + 1;
            }
            return v;
        }() + "f 1 2 3\nf 1 3 4\nf 2 1 5\nf 1 4 5\nf 4 3 5\nf 3 2 5\n");
    Report report;
    const auto cloud = import(file, report);
    expect_triangulated_pyramid(cloud);
    EXPECT_TRUE(report.normals_area_weighted);
    EXPECT_EQ(report.faces, 6u);
    EXPECT_NE(report.reader.find("obj"), std::string::npos);
}

TEST_F(MeshTest, OffQuadBaseAreaWeightedNormals) {
    const auto file = write("pyramid.off", std::string("OFF\n5 5 0\n") + k_pyramid_vertices +
                                               "4 0 1 2 3\n3 1 0 4\n3 0 3 4\n3 3 2 4\n3 2 1 4\n");
    Report report;
    const auto cloud = import(file, report);
    ASSERT_EQ(cloud.size(), 5u);
    // The quad base contributes (0,0,-8) to all four corners.
    expect_normal(cloud.normals[0], 2, 2, -4, "v0");   // (2,0,2)+(0,2,2)+(0,0,-8)
    expect_normal(cloud.normals[1], 2, -2, -4, "v1");  // (2,0,2)+(0,-2,2)+(0,0,-8)
    expect_normal(cloud.normals[2], -2, -2, -4, "v2");
    expect_normal(cloud.normals[3], -2, 2, -4, "v3");
    expect_normal(cloud.normals[4], 0, 0, 1, "apex");
    EXPECT_EQ(report.faces, 5u);
}

std::string stl_binary(const std::vector<std::array<std::array<float, 3>, 3>>& tris) {
    std::string out(80, ' ');
    put<std::uint32_t>(out, static_cast<std::uint32_t>(tris.size()));
    for (const auto& t : tris) {
        for (int i = 0; i < 3; ++i) put<float>(out, 0.f);  // facet normal: ignored, we compute our own
        for (const auto& v : t)
            for (float c : v) put<float>(out, c);
        put<std::uint16_t>(out, 0);
    }
    return out;
}

TEST_F(MeshTest, StlBinaryAndAsciiAreaWeightedNormals) {
    const std::array<float, 3> v0{1, 1, 0}, v1{1, -1, 0}, v2{-1, -1, 0}, v3{-1, 1, 0}, v4{0, 0, 1};
    const std::vector<std::array<std::array<float, 3>, 3>> tris = {{v0, v1, v2}, {v0, v2, v3}, {v1, v0, v4},
                                                                   {v0, v3, v4}, {v3, v2, v4}, {v2, v1, v4}};
    {
        const auto file = write("pyramid.stl", stl_binary(tris));
        Report report;
        expect_triangulated_pyramid(import(file, report));
    }
    {
        std::string text = "solid pyramid\n";
        for (const auto& t : tris) {
            text += "facet normal 0 0 0\nouter loop\n";
            for (const auto& v : t) {
                char buf[128];
                std::snprintf(buf, sizeof buf, "vertex %g %g %g\n", v[0], v[1], v[2]);
                text += buf;
            }
            text += "endloop\nendfacet\n";
        }
        text += "endsolid pyramid\n";
        const auto file = write("pyramid_ascii.stl", text);
        Report report;
        expect_triangulated_pyramid(import(file, report));
    }
}

// A PLY with faces and no normals is a mesh by default; --mesh-mode points reads its vertices.
TEST_F(MeshTest, PlyWithFacesMeshModes) {
    const auto file = write(
        "pyramid.ply", std::string("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
                                   "property float y\nproperty float z\nelement face 6\n"
                                   "property list uchar int vertex_indices\nend_header\n") +
                           k_pyramid_vertices + "3 0 1 2\n3 0 2 3\n3 1 0 4\n3 0 3 4\n3 3 2 4\n3 2 1 4\n");
    Report report;
    expect_triangulated_pyramid(import(file, report));
    EXPECT_NE(report.reader.find("mesh"), std::string::npos) << report.reader;

    Options points;
    points.mesh_mode = prt::pre::import::MeshMode::points;
    points.normals = prt::pre::import::NormalsMode::keep;
    Report report2;
    const auto cloud = import(file, report2, points);
    EXPECT_EQ(cloud.size(), 5u);
    EXPECT_FALSE(cloud.has_normals());
    EXPECT_NE(report2.reader.find("ply (ascii)"), std::string::npos) << report2.reader;
}

// Vertices on no face have no area-weighted normal: dropped and counted. Faces with a bad index
// are skipped and counted. Double-sided faces cancel: counted.
TEST_F(MeshTest, UnreferencedVerticesAndCancellingFaces) {
    const auto file =
        write("extra.off", "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n5 5 5\n0 0 1\n3 0 1 2\n3 0 2 1\n3 0 1 4\n");
    Report report;
    const auto cloud = import(file, report);
    EXPECT_EQ(report.unreferenced_vertices, 1u);  // v3
    // v2 lies only on the two opposite copies of the same triangle: its normals cancel.
    EXPECT_EQ(report.cancelled_normals, 1u);
    EXPECT_EQ(report.clean.zero_normal, 2u);
    EXPECT_EQ(cloud.size(), 3u);
}

TEST_F(MeshTest, BadMeshFilesFailWithOneLine) {
    const BadFile cases[] = {
        {"empty.obj", "", "file is empty"},
        {"empty.off", "", "file is empty"},
        {"noface.obj", "v 0 0 0\nv 1 0 0\n", "no faces"},
        {"garbage.off", "OFF\nthis is not a mesh\n", "OFF vertex count 'this' is not a non-negative integer"},
        {"garbage.stl", std::string(40, '\x07'), "not an STL file"},
        // Header checks before OpenMesh (which trusts counts and can loop on bad ones):
        {"counts.off", "OFF\n1000000 2 0\n0 0 0\n",
         "declares 1000000 vertices and 2 faces but the file has only"},
        {"negative.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n-1 0 1 2\n",
         "line 6: face 0 is not 'n i_1 .. i_n'"},
        {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
         "face 0 has vertex index '7' (the file has 3"},
        {"short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n", "declares 1 faces but the file ends after 0"},
        {"vertex.off", "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", "line 4: vertex 1 has fewer than 3"},
        {"noff.off", "MESH\n", "not an OFF file"},
        {"bad_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperXy float x\nend_header\n",
         "unknown PLY header keyword"},
    };
    expect_one_line_errors(cases);
}

// ---- sampling -----------------------------------------------------------------------------------

// The cube [-1,1]^3 as 12 outward-wound triangles.
std::string cube_obj() {
    std::string s;
    for (int i = 0; i < 8; ++i)
        s += "v " + std::to_string((i & 1) ? 1 : -1) + " " + std::to_string((i & 2) ? 1 : -1) + " " +
             std::to_string((i & 4) ? 1 : -1) + "\n";
    // vertex index (1-based) = 1 + x + 2y + 4z
    s += "f 1 3 4\nf 1 4 2\n"   // z = -1, outward -z
         "f 5 6 8\nf 5 8 7\n"   // z = +1
         "f 1 2 6\nf 1 6 5\n"   // y = -1
         "f 3 7 8\nf 3 8 4\n"   // y = +1
         "f 1 5 7\nf 1 7 3\n"   // x = -1
         "f 2 4 8\nf 2 8 6\n";  // x = +1
    return s;
}

TEST_F(MeshTest, SampledPointsLieOnTheSurfaceUniformlyWithFaceNormals) {
    const auto file = write("cube.obj", cube_obj());
    Options options;
    options.sample = 6000;
    options.seed = 7;
    Report report;
    const auto cloud = import(file, report, options);
    ASSERT_EQ(cloud.size(), 6000u);
    EXPECT_EQ(report.clean.duplicates, 0u);
    std::map<int, int> per_face;  // key: axis * 2 + (positive side)
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = cloud.positions[i];
        int face = -1;
        for (int a = 0; a < 3; ++a) {
            EXPECT_LE(std::fabs(p[a]), 1.0 + 1e-12);
            if (std::fabs(std::fabs(p[a]) - 1.0) < 1e-12) face = a * 2 + (p[a] > 0);
        }
        ASSERT_GE(face, 0) << "point " << i << " is not on the cube surface";
        ++per_face[face];
        const float n[3] = {cloud.normals[i].x, cloud.normals[i].y, cloud.normals[i].z};
        const int axis = face / 2;
        EXPECT_NEAR(n[axis], (face & 1) ? 1.f : -1.f, 1e-6) << "outward face normal";
    }
    // Uniform by area: each face expects 1000, binomial sigma = sqrt(6000 * 1/6 * 5/6) ~ 29.
    ASSERT_EQ(per_face.size(), 6u);
    for (const auto& [face, count] : per_face) EXPECT_NEAR(count, 1000, 5 * 29) << "face " << face;
    EXPECT_NE(report.normals_detail.find("face normals"), std::string::npos);

    // Same seed, same points; another seed, other points.
    Report again;
    EXPECT_EQ(import(file, again, options).positions, cloud.positions);
    options.seed = 8;
    Report other;
    EXPECT_NE(import(file, other, options).positions, cloud.positions);
}

TEST_F(MeshTest, SampledInterpolatedNormalsBlendVertexNormals) {
    const auto file = write("cube.obj", cube_obj());
    Options options;
    options.sample = 500;
    options.sample_normals = prt::pre::import::SampleNormals::interpolated;
    Report report;
    const auto cloud = import(file, report, options);
    ASSERT_EQ(cloud.size(), 500u);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = cloud.positions[i];
        const auto& n = cloud.normals[i];
        // Pointing outward (positive along the position) but not axis-aligned: corner normals blend.
        EXPECT_GT(n.x * p[0] + n.y * p[1] + n.z * p[2], 0.0);
        EXPECT_NEAR(n.x * n.x + n.y * n.y + n.z * n.z, 1.0, 1e-5);
    }
}

// Checked before any reading: needs no OpenMesh.
using MeshOptions = TempDirTest;
TEST_F(MeshOptions, SampleNeedsAMesh) {
    const auto file = write("p.xyz", "0 0 0\n1 1 1\n");
    Options options;
    options.sample = 10;
    Report report;
    EXPECT_NE(error_of([&] { import(file, report, options); }).find("--sample needs a mesh"),
              std::string::npos);
}

// The geometry functions alone (no OpenMesh): a non-planar quad's Newell vector.
TEST(MeshGeometry, NewellVectorOfAQuad) {
    prt::pre::import::MeshData mesh;
    mesh.vertices = {{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 0}};
    mesh.face_begin = {0, 4};
    mesh.face_indices = {0, 1, 2, 3};
    const auto a = prt::pre::import::face_area_vector(mesh, 0);
    EXPECT_DOUBLE_EQ(a[2], 12.0);  // twice the area 2 x 3, along +z
    EXPECT_DOUBLE_EQ(a[0], 0.0);
    EXPECT_DOUBLE_EQ(a[1], 0.0);
}

}  // namespace
