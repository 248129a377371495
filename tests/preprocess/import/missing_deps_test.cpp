// Builds without PCL or OpenMesh: their paths fail with one line saying what the build lacks
// (skipped in builds that have them: those paths are tested elsewhere); normals need neither.
#include "import_test_util.h"

namespace {

using namespace prt_import_test;
using MissingDeps = TempDirTest;

TEST_F(MissingDeps, PcdAndEstimationWithoutPcl) {
    if (prt::pre::import::have_pcl()) GTEST_SKIP() << "this build has PCL";
    const auto pcd = write("a.pcd",
                           "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                           "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n");
    prt::pre::import::Report report;
    const std::string msg = error_of([&] { import(pcd, report); });
    EXPECT_NE(msg.find("has no PCL"), std::string::npos) << msg;
    // Normal estimation is ours (neighbours.h): it works without PCL.
    const auto xyz = write("a.xyz", "0 0 0\n1 0 0\n0 1 0\n1 1 0.1\n");
    prt::pre::import::Report report2;
    const auto cloud = import(xyz, report2);
    EXPECT_TRUE(cloud.has_normals());
    EXPECT_TRUE(report2.normals_estimated);
}

TEST_F(MissingDeps, MeshesWithoutOpenMesh) {
    if (prt::pre::import::have_openmesh()) GTEST_SKIP() << "this build has OpenMesh";
    const auto obj = write("a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    prt::pre::import::Report report;
    const std::string msg = error_of([&] { import(obj, report); });
    EXPECT_NE(msg.find("has no OpenMesh"), std::string::npos) << msg;
}

}  // namespace
