// Test-only helpers: pools of every surface kind made by the real tools (prt-synth, prt-radii,
// prt-octree, prt-iso, prt-mls, prt-patches) in a temporary folder, and an analytic ray-sphere
// intersection to check hits against. Shared by surfaces_test.cpp (CPU) and backend_gpu_test.cpp.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "tool_run.h"

namespace prt::test {

/// A temporary folder removed with the object.
struct TempDir {
    std::filesystem::path path;
    explicit TempDir(const std::string& name)
        : path(std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~TempDir() { std::filesystem::remove_all(path); }
};

/// Whether the tools these fixtures run were built (prt-radii needs FLANN); tests skip otherwise.
inline bool surface_tools_built(std::string* missing = nullptr) {
    for (const char* t : {"prt-synth", "prt-radii", "prt-octree", "prt-iso", "prt-mls", "prt-patches"}) {
        if (!std::filesystem::exists(std::filesystem::path(PRT_BIN_DIR) / t)) {
            if (missing) *missing = t;
            return false;
        }
    }
    return true;
}

/// Skips the current test when a tool is missing.
#define PRT_SKIP_WITHOUT_SURFACE_TOOLS()                                                          \
    do {                                                                                          \
        std::string missing_tool_;                                                                \
        if (!::prt::test::surface_tools_built(&missing_tool_))                                    \
            GTEST_SKIP() << missing_tool_ << " was not built (prt-radii needs FLANN): no test pools"; \
    } while (0)

/// Runs a tool and fails the test with its stderr when it fails.
inline void must_run(const std::string& tool, const std::string& args, const std::filesystem::path& dir) {
    const ToolRun r = run_tool(tool, args, dir);
    ASSERT_EQ(r.code, 0) << tool << " " << args << ": " << r.err;
}

/// A unit sphere of `points` points at the origin with splat, ISO and MLS sections (prt-synth ->
/// prt-radii -> prt-octree -> prt-iso -> prt-mls).
inline std::filesystem::path sphere_pool_all_surfaces(const std::filesystem::path& dir, unsigned points,
                                                      const std::string& iso_args = "--storage both") {
    const std::filesystem::path p = dir / "sphere.pool";
    const std::string q = " -q";
    must_run("prt-synth", "sphere -n " + std::to_string(points) + " -o " + p.string() + q, dir);
    must_run("prt-radii", p.string() + " -o " + p.string() + q, dir);
    must_run("prt-octree", p.string() + " -o " + p.string() + q, dir);
    must_run("prt-iso", p.string() + " -o " + p.string() + " " + iso_args + q, dir);
    must_run("prt-mls", p.string() + " -o " + p.string() + q, dir);
    return p;
}

/// A .bpt file (seed 002's patch format) of one flat bicubic patch: the square [x0,x0+size] x
/// [y0,y0+size] in the plane z = z0, control points evenly spaced (so Q(u,v) is affine), its
/// normal dQ/du x dQ/dv = +z (the front face looks up the z axis).
inline std::filesystem::path flat_patch_file(const std::filesystem::path& dir, double x0, double y0, double z0,
                                             double size, const std::string& name = "flat.bpt") {
    const std::filesystem::path p = dir / name;
    std::ofstream out(p);
    out << "1\n3 3\n";
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) out << x0 + size * i / 3.0 << " " << y0 + size * j / 3.0 << " " << z0 << "\n";
    return p;
}

/// The nearest t > 0 where o + t d (d unit) meets the sphere |x - c| = r, or -1.
inline double ray_sphere(const double o[3], const double d[3], const double c[3], double r) {
    const double oc[3] = {o[0] - c[0], o[1] - c[1], o[2] - c[2]};
    const double b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
    const double cc = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - r * r;
    const double disc = b * b - cc;
    if (disc < 0) return -1;
    const double s = std::sqrt(disc);
    if (-b - s > 0) return -b - s;
    if (-b + s > 0) return -b + s;
    return -1;
}

}  // namespace prt::test
