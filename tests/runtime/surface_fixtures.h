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

#include "test_scene.h"
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
#define PRT_SKIP_WITHOUT_SURFACE_TOOLS()                                                              \
    do {                                                                                              \
        std::string missing_tool_;                                                                    \
        if (!::prt::test::surface_tools_built(&missing_tool_))                                        \
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
inline std::filesystem::path flat_patch_file(const std::filesystem::path& dir, double x0, double y0,
                                             double z0, double size, const std::string& name = "flat.bpt") {
    const std::filesystem::path p = dir / name;
    std::ofstream out(p);
    out << "1\n3 3\n";
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            out << x0 + size * i / 3.0 << " " << y0 + size * j / 3.0 << " " << z0 << "\n";
    return p;
}

/// A .bpt file of a sphere of radius `r` at `center` in 8 bicubic patches (4 around x 2
/// hemispheres): Q(u, v) = (r(u) c(v), z(u)) with the profile (r, z) and the unit circle c each a
/// quarter circle as a cubic Bezier (inner control points at k = 4 (sqrt 2 - 1) / 3), so the patches
/// are tensor products of the two; the surface lies within 5e-4 r of the sphere. Normals
/// dQ/du x dQ/dv point outward, or inward with `inward`, on every patch (the poles collapse an
/// edge: the core takes the normal's limit there).
inline std::filesystem::path sphere_patch_file(const std::filesystem::path& dir, double r,
                                               const double center[3], bool inward = false,
                                               const std::string& name = "sphere.bpt") {
    const double k = 4.0 * (std::sqrt(2.0) - 1.0) / 3.0;
    const double prof[4][2] = {{1, 0}, {1, k}, {k, 1}, {0, 1}};  // (radius, height): equator -> pole
    const double circ[4][2] = {{1, 0}, {1, k}, {k, 1}, {0, 1}};  // quarter of the unit circle
    const std::filesystem::path p = dir / name;
    std::ofstream out(p);
    out.precision(17);
    out << "8\n";
    for (int hemi = 0; hemi < 2; ++hemi)
        for (int q = 0; q < 4; ++q) {
            out << "3 3\n";
            const double a = q * M_PI / 2, ca = std::cos(a), sa = std::sin(a);
            // Upper hemisphere with v running counter-clockwise gives dQ/du x dQ/dv inward; the
            // lower one (heights negated) outward: reverse v where the wanted side differs.
            const bool reverse_v = (hemi == 0) != inward;
            for (int i = 0; i < 4; ++i)
                for (int jj = 0; jj < 4; ++jj) {
                    const int j = reverse_v ? 3 - jj : jj;
                    const double cx = circ[j][0] * ca - circ[j][1] * sa,
                                 cy = circ[j][0] * sa + circ[j][1] * ca;
                    const double z = hemi == 0 ? prof[i][1] : -prof[i][1];
                    out << center[0] + r * prof[i][0] * cx << " " << center[1] + r * prof[i][0] * cy << " "
                        << center[2] + r * z << "\n";
                }
        }
    return p;
}

/// Two spheres of `pool` (the unit sphere) as surface `kind` reflecting each other: one glossy, one
/// a pure mirror (diffuse reflectance 0: shaded black), a light with shadow rays and one without,
/// the camera on both (the shared-walk tests: surfaces_test.cpp, backend_gpu_test.cpp).
inline scene::Scene mirror_spheres_scene(const std::filesystem::path& pool, scene::SurfaceKind kind) {
    scene::Scene sc;
    scene::Material glossy, pure;
    glossy.reflectivity = 0.5f;
    glossy.diffuse_reflectance = 0.5f;
    pure.reflectivity = 0.9f;
    pure.diffuse_reflectance = 0.0f;
    sc.materials = {glossy, pure};
    scene::Model a, b;
    a.pool = b.pool = pool;
    a.surface = b.surface = kind;
    b.material = 1;
    b.transform.translate = {2.3, 0.4, 0};
    sc.models = {a, b};
    sc.camera.position = {1.2, 1.0, 4.5};
    sc.camera.look_at = {1.1, 0.1, 0};
    scene::PointLight shadowed, unshadowed;
    shadowed.position = {4, 3, 1};
    unshadowed.position = {-3, 2, 2};
    unshadowed.casts_shadows = false;
    sc.point_lights = {shadowed, unshadowed};
    return sc;
}

/// Writes a test model's points only (model info, positions, normals, radii, colors): no octree, as
/// a scan traced only as ISO or MLS comes.
inline void write_points_pool(const TestModel& m, const std::filesystem::path& path) {
    const auto full = make_pool(m);
    pool::PoolWriter w;
    w.carry_over(*full);
    for (pool::SectionType t : {pool::SectionType::octree_info, pool::SectionType::octree_nodes,
                                pool::SectionType::leaf_info, pool::SectionType::splats})
        w.remove(t);
    w.write(path);
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
