// Environment maps (thesis fig. 4.11: a refractive object against an environment map; SCENE.md
// environment.image: a latitude-longitude HDR image, +y up, row 0 = up). Checks that an HDR
// image read from disk (.hdr written byte by byte here, .exr through OpenImageIO) is what rays
// that leave the scene see: directly (background), after a mirror, and through a glass sphere.
//
// The lat-long convention checked (runtime/core shading.h background()): a unit direction d has
// longitude phi = atan2(d.x, -d.z) (0 straight ahead along -z, +pi/2 towards +x) and column
// u = 0.5 + phi / (2 pi); colatitude theta = acos(d.y) and row v = theta / pi (v = 0: +y, the
// image's top row). The test image stores at each texel the direction of its centre, encoded as
// color = 2 + d (every value in [1, 3], above 1: HDR), so the color a ray brings back names the
// direction it left in. Expected directions are computed here in double from the geometry.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "prt/core/shading.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/runtime/image.h"
#include "prt/runtime/render_scene.h"
#include "test_scene.h"

namespace prt::test {
namespace {

namespace fs = std::filesystem;
constexpr double k_pi = 3.14159265358979323846;

/// The unit direction at lat-long image coordinates (u, v) in [0, 1]^2 (the convention above).
D3 latlong_direction(double u, double v) {
    const double phi = (u - 0.5) * 2.0 * k_pi, theta = v * k_pi;
    return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

/// A W x H lat-long image whose texel stores 2 + (the direction of its centre).
rt::Image direction_image(std::uint32_t w, std::uint32_t h) {
    rt::Image img;
    img.resize(w, h);
    for (std::uint32_t y = 0; y < h; ++y)
        for (std::uint32_t x = 0; x < w; ++x) {
            const D3 d = latlong_direction((x + 0.5) / w, (y + 0.5) / h);
            for (int c = 0; c < 3; ++c)
                img.rgb[(static_cast<std::size_t>(y) * w + x) * 3 + c] = float(2.0 + d[c]);
        }
    return img;
}

/// The direction a color of direction_image() encodes.
D3 decode(const float* rgb) {
    return d3_norm({rgb[0] - 2.0, rgb[1] - 2.0, rgb[2] - 2.0});
}

double angle(const D3& a, const D3& b) {
    return std::acos(std::clamp(d3_dot(d3_norm(a), d3_norm(b)), -1.0, 1.0));
}

/// Radiance RGBE encoding of one pixel (Ward, Graphics Gems II "Real pixels").
void rgbe(const float c[3], unsigned char out[4]) {
    const double v = std::max({c[0], c[1], c[2]});
    if (v < 1e-32) {
        out[0] = out[1] = out[2] = out[3] = 0;
        return;
    }
    int e = 0;
    const double scale = std::frexp(v, &e) * 256.0 / v;
    for (int i = 0; i < 3; ++i) out[i] = static_cast<unsigned char>(c[i] * scale);
    out[3] = static_cast<unsigned char>(e + 128);
}

/// Writes `img` as an uncompressed Radiance .hdr, rows from the top ("-Y H +X W"), written here
/// byte by byte so the reader is checked against the format, not against the project's writer.
void write_hdr(const fs::path& path, const rt::Image& img) {
    std::ofstream out(path, std::ios::binary);
    out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " << img.height << " +X " << img.width << "\n";
    for (std::size_t i = 0; i < static_cast<std::size_t>(img.width) * img.height; ++i) {
        unsigned char px[4];
        rgbe(&img.rgb[i * 3], px);
        out.write(reinterpret_cast<const char*>(px), 4);
    }
}

class Environment : public ::testing::Test {
protected:
    void SetUp() override {
        if (!rt::have_oiio())
            GTEST_SKIP() << "this build has no OpenImageIO: .exr/.hdr environment maps untested";
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() / ("prt_env_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
        m_exr = m_dir / "sky.exr";
        rt::write_image(m_exr, direction_image(k_w, k_h));
    }
    void TearDown() override {
        if (!m_dir.empty()) fs::remove_all(m_dir);
    }

    /// Renders `sc` with the CPU backend and returns the linear image.
    static rt::Image render(const rt::RenderScene& rs) {
        auto backend = cpu::make_cpu_backend(0);
        backend->set_scene(rs.view());
        rt::FrameRequest req;
        req.camera = rs.camera();
        req.params = rs.params();
        req.width = rs.scene().camera.width;
        req.height = rs.scene().camera.height;
        rt::Image img;
        backend->render(req, img);
        return img;
    }
    /// The primary ray direction through pixel (x, y)'s centre of a scene camera (row 0 at the top).
    static D3 pixel_direction(const scene::Camera& c, std::uint32_t x, std::uint32_t y) {
        const D3 f = d3_norm(d3_sub(c.look_at, c.position));
        const D3 up{c.up[0], c.up[1], c.up[2]};
        const D3 r =
            d3_norm({f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]});
        const D3 u{r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]};
        const double half = std::tan(0.5 * c.fov_y_degrees * k_pi / 180.0);
        const double aspect = double(c.width) / c.height;
        const double sx = (2.0 * (x + 0.5) / c.width - 1.0) * half * aspect,
                     sy = (1.0 - 2.0 * (y + 0.5) / c.height) * half;
        return d3_norm(d3_add(f, d3_add(d3_mul(r, sx), d3_mul(u, sy))));
    }
    static scene::Scene base_scene(const fs::path& env) {
        scene::Scene s;
        scene::Material m;
        m.ambient = {0, 0, 0};
        m.specular = {0, 0, 0};
        s.materials.push_back(m);
        s.environment.image = env;
        s.environment.intensity = 1.0f;
        s.camera.width = 48;
        s.camera.height = 48;
        s.camera.fov_y_degrees = 60;
        return s;
    }

    static constexpr std::uint32_t k_w = 256, k_h = 128;
    static constexpr double k_texel = 2.0 * k_pi / k_w;  ///< 1.4 degrees
    /// Bilinear interpolation of unit vectors a texel apart bends the decoded direction by a
    /// second-order amount only (measured: at most 0.002 degrees); a tenth of a texel is the
    /// tolerance of a path without splat normals in it. A half-texel shift of the convention
    /// (0.7 degrees) or any flip fails it.
    static constexpr double k_exact = k_texel / 10.0;
    fs::path m_dir, m_exr;
};

TEST(ImageFiles, PpmReadsAsLevelsOver255InEveryBuild) {
    // The screenshot format of builds without OpenImageIO reads back as 8-bit levels / 255.
    rt::Image img;
    img.resize(3, 2);
    for (std::uint32_t i = 0; i < 6; ++i)
        img.rgba8[i] = (i * 40u) | ((255u - i * 30u) << 8) | ((i * 7u) << 16) | 0xff000000u;
    const fs::path file = fs::temp_directory_path() / ("prt_ppm_" + std::to_string(::getpid()) + ".ppm");
    rt::write_ppm(file, img);
    const rt::FloatImage r = rt::read_float_image(file);
    fs::remove(file);
    ASSERT_EQ(r.width, 3u);
    ASSERT_EQ(r.height, 2u);
    for (std::uint32_t i = 0; i < 6; ++i) {
        EXPECT_FLOAT_EQ(r.rgb[3 * i], float(i * 40u) / 255.0f) << i;
        EXPECT_FLOAT_EQ(r.rgb[3 * i + 1], float(255u - i * 30u) / 255.0f) << i;
        EXPECT_FLOAT_EQ(r.rgb[3 * i + 2], float(i * 7u) / 255.0f) << i;
    }
}

TEST_F(Environment, HdrAndExrLoadAsLinearRowZeroUp) {
    // An HDR image with values above 1 and a marked top row, through the .hdr and .exr readers.
    rt::Image img;
    img.resize(4, 3);
    for (std::uint32_t y = 0; y < 3; ++y)
        for (std::uint32_t x = 0; x < 4; ++x)
            for (int c = 0; c < 3; ++c)
                img.rgb[(y * 4 + x) * 3 + c] = y == 0 ? 40.0f : float(1 + x) * (c + 1) * 0.75f;
    write_hdr(m_dir / "t.hdr", img);
    rt::write_image(m_dir / "t.exr", img);
    for (const char* name : {"t.hdr", "t.exr"}) {
        SCOPED_TRACE(name);
        const rt::FloatImage r = rt::read_float_image(m_dir / name);
        ASSERT_EQ(r.width, 4u);
        ASSERT_EQ(r.height, 3u);
        for (std::size_t i = 0; i < r.rgb.size(); ++i)
            EXPECT_NEAR(r.rgb[i], img.rgb[i], img.rgb[i] / 64.0) << "element " << i;  // RGBE: 8-bit mantissa
    }
    const rt::FloatImage exr = rt::read_float_image(m_exr);
    ASSERT_EQ(exr.width, k_w);
    EXPECT_EQ(exr.rgb[1], float(2.0 + latlong_direction(0.5 / k_w, 0.5 / k_h)[1])) << "EXR floats are exact";
    EXPECT_GT(exr.rgb[1], 2.99f) << "row 0 is the top (+y)";
}

TEST_F(Environment, BackgroundShowsTheImageAtThePixelsDirection) {
    // A small sphere behind the camera gives the scene a model; every pixel sees the background.
    const auto pts = sphere_points({0, 0, 40}, 1.0, 2000);
    for (const D3& look : {D3{0, 0, -1}, D3{1, 0.3, 0.2}, D3{-0.2, -0.5, 1e-3}}) {
        scene::Scene sc = base_scene(m_exr);
        sc.camera.position = {0, 0, 0};
        sc.camera.look_at = look;
        if (look[2] > 0) sc.camera.position = {0, 0, -80};  // keep the sphere out of view
        if (look[2] > 0) sc.camera.look_at = d3_add(sc.camera.position, look);
        const rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0, 40}))});
        const rt::Image img = render(rs);
        double worst = 0;
        for (std::uint32_t y = 0; y < 48; y += 3)
            for (std::uint32_t x = 0; x < 48; x += 3) {
                const D3 want = pixel_direction(sc.camera, x, y);
                worst = std::max(worst, angle(decode(&img.rgb[(y * 48 + x) * 3]), want));
            }
        RecordProperty("background_worst_degrees_" + std::to_string(int(look[0] * 10)),
                       std::to_string(worst * 180 / k_pi));
        EXPECT_LT(worst, k_exact) << "looking along " << look[0] << " " << look[1] << " " << look[2];
    }
    // The core lookup on its own, all over the sphere (away from the poles, where rows clamp).
    const rt::FloatImage env = rt::read_float_image(m_exr);
    core::EnvironmentView view;
    view.image = env.rgb.data();
    view.width = env.width;
    view.height = env.height;
    for (int i = 0; i < 400; ++i) {
        const D3 d =
            latlong_direction((i * 0.618034) - std::floor(i * 0.618034), 0.05 + 0.9 * (i + 0.5) / 400);
        const core::Vec3 c = core::background(view, core::Vec3{float(d[0]), float(d[1]), float(d[2])});
        const float rgb[3] = {c.x, c.y, c.z};
        EXPECT_LT(angle(decode(rgb), d), k_exact) << "direction " << d[0] << " " << d[1] << " " << d[2];
    }
    // Degenerate directions give a finite color.
    for (const core::Vec3 d :
         {core::Vec3{0, 1, 0}, core::Vec3{0, -1, 0}, core::Vec3{NAN, 0, 0}, core::Vec3{0, 0, 0}})
        EXPECT_TRUE(core::is_finite(core::background(view, d)));
}

TEST_F(Environment, MirrorReflectsTheImage) {
    // A mirror plane z = -2 (normal +z) seen from the origin: the color is the environment along
    // the mirrored direction (d.x, d.y, -d.z).
    const TestModel plane =
        make_model(rect_points({-6, -6, -2}, {12, 0, 0}, {0, 12, 0}, {0, 0, 1}, 160), {0, 0, -2});
    scene::Scene sc = base_scene(m_exr);
    sc.materials[0].reflectivity = 1.0f;
    sc.materials[0].diffuse_reflectance = 0.0f;
    sc.camera.position = {0, 0, 0};
    sc.camera.look_at = {0.3, 0.2, -1};
    const rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(plane)});
    const rt::Image img = render(rs);
    double worst = 0, unreflected = 1e9;
    for (std::uint32_t y = 0; y < 48; y += 3)
        for (std::uint32_t x = 0; x < 48; x += 3) {
            const D3 d = pixel_direction(sc.camera, x, y);
            const D3 got = decode(&img.rgb[(y * 48 + x) * 3]);
            worst = std::max(worst, angle(got, {d[0], d[1], -d[2]}));
            unreflected = std::min(unreflected, angle(got, d));
        }
    RecordProperty("mirror_worst_degrees", std::to_string(worst * 180 / k_pi));
    EXPECT_LT(worst, k_exact) << "the mirror shows the environment along the reflected direction";
    EXPECT_GT(unreflected, 10 * k_texel) << "control: no pixel shows the unreflected direction";
}

/// Snell refraction of unit d at unit normal n (facing against d), eta = n1 / n2, double.
bool refract_d(const D3& d, const D3& n, double eta, D3& t) {
    const double ci = -d3_dot(d, n);
    const double s2 = eta * eta * (1 - ci * ci);
    if (s2 > 1) return false;
    t = d3_norm(d3_add(d3_mul(d, eta), d3_mul(n, eta * ci - std::sqrt(1 - s2))));
    return true;
}

TEST_F(Environment, GlassSphereRefractsTheImage) {
    // thesis fig. 4.11: a refracting object against an environment map. A unit glass sphere
    // (n = 1.5, fully transmissive) seen from z = 4: each pixel's ray refracts in and out at the
    // true sphere (double precision here) and brings back the environment along the exit direction.
    const double ior = 1.5;
    const auto pts = sphere_points({0, 0, 0}, 1.0, 60000);
    scene::Scene sc = base_scene(m_exr);
    sc.materials[0].transmissivity = 1.0f;
    sc.materials[0].diffuse_reflectance = 0.0f;
    sc.materials[0].refractive_index = float(ior);
    sc.camera.position = {0.0, 0.0, 4.0};
    sc.camera.look_at = {0, 0, 0};
    sc.camera.fov_y_degrees = 35;
    const rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0, 0}))});
    const rt::Image img = render(rs);
    const D3 o{0, 0, 4};
    double worst = 0, bend = 0;
    int inside = 0;
    for (std::uint32_t y = 0; y < 48; y += 2)
        for (std::uint32_t x = 0; x < 48; x += 2) {
            const D3 d = pixel_direction(sc.camera, x, y);
            // Entry: |o + t d| = 1; rays with impact parameter above 0.85 graze the rim, where
            // splat normals are least accurate, and are left out.
            const double b = d3_dot(o, d), impact = std::sqrt(std::max(0.0, d3_dot(o, o) - b * b));
            if (impact > 0.85) continue;
            const D3 p1 = d3_add(o, d3_mul(d, -b - std::sqrt(b * b - d3_dot(o, o) + 1)));
            D3 t1, t2;
            ASSERT_TRUE(refract_d(d, p1, 1.0 / ior, t1));
            const D3 p2 = d3_add(p1, d3_mul(t1, -2.0 * d3_dot(p1, t1)));  // the chord's other end
            ASSERT_TRUE(refract_d(t1, d3_mul(p2, -1.0), ior, t2));
            worst = std::max(worst, angle(decode(&img.rgb[(y * 48 + x) * 3]), t2));
            bend = std::max(bend, angle(t2, d));
            ++inside;
        }
    EXPECT_GT(inside, 100);
    // Splat normals deviate from the true sphere's by up to about r / R (render_test.cpp), but the
    // blended normals of thesis 3.3 come much closer: measured 0.13 degrees at most against a
    // tolerance of r / (2 R) = 0.7 degrees (r / R: the splat radius over the sphere's).
    const double tolerance = 0.5 * pts[0].radius;
    RecordProperty("glass_worst_degrees", std::to_string(worst * 180 / k_pi));
    RecordProperty("glass_tolerance_degrees", std::to_string(tolerance * 180 / k_pi));
    RecordProperty("glass_max_bend_degrees", std::to_string(bend * 180 / k_pi));
    EXPECT_LT(worst, tolerance) << "the sphere shows the environment along the refracted direction";
    EXPECT_GT(bend, 4 * tolerance) << "control: refraction must bend the rays measurably";
}

}  // namespace
}  // namespace prt::test
