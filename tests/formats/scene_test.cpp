// Scene description tests: defaults, round trip, strict errors with JSON paths, path resolution.
// References are written out by hand from formats/SCENE.md, never taken from the parser's output.
#include "prt/formats/scene.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace prt::scene;

namespace {

/// The message of the prt::Error that parsing `text` throws ("" when it does not throw).
std::string error_of(const std::string& text, const fs::path& base = {}) {
    try {
        parse_scene(text, "t.json", base);
    } catch (const prt::Error& e) {
        return e.what();
    }
    return "";
}

/// A fresh empty folder under the system temp folder, removed at the end of the test.
class TempDir {
public:
    TempDir() {
        static std::atomic<int> counter{0};
        m_path = fs::temp_directory_path() /
                 ("prt_scene_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        fs::remove_all(m_path);
        fs::create_directories(m_path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    const fs::path& path() const { return m_path; }

private:
    fs::path m_path;
};

void write_file(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << text;
}

}  // namespace

TEST(Scene, EmptyObjectGivesDocumentedDefaults) {
    const Scene s = parse_scene("{}", "t.json");
    // SCENE.md: camera at (0,0,5) looking at the origin, y up, 45 degrees, 512 x 512.
    EXPECT_EQ(s.camera.position, (Vec3{0, 0, 5}));
    EXPECT_EQ(s.camera.look_at, (Vec3{0, 0, 0}));
    EXPECT_EQ(s.camera.up, (Vec3{0, 1, 0}));
    EXPECT_EQ(s.camera.fov_y_degrees, 45.0);
    EXPECT_EQ(s.camera.width, 512u);
    EXPECT_EQ(s.camera.height, 512u);
    EXPECT_TRUE(s.point_lights.empty());
    EXPECT_TRUE(s.area_lights.empty());
    ASSERT_EQ(s.materials.size(), 1u);  // the default material
    EXPECT_EQ(s.materials[0].name, "default");
    EXPECT_EQ(s.materials[0].diffuse, (Color{0.8f, 0.8f, 0.8f}));
    EXPECT_EQ(s.materials[0].diffuse_reflectance, 1.0f);
    EXPECT_TRUE(s.models.empty());
    EXPECT_EQ(s.render.max_bounces, 4u);
    EXPECT_EQ(s.render.spp, 1u);
    EXPECT_FALSE(s.render.caustics);
    EXPECT_TRUE(s.file.empty());
}

TEST(Scene, ReadsEveryKey) {
    const std::string text = R"({
      "camera": {"position": [1, 2, 3], "look_at": [0, 1, 0], "up": [0, 0, 1],
                 "fov_y_degrees": 60, "width": 640, "height": 480},
      "lights": [
        {"type": "point", "position": [0, 4, 0], "color": [1, 0.5, 0.25], "intensity": 3,
         "casts_shadows": false},
        {"type": "area", "corner": [-1, 3, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2],
         "color": [2, 2, 2], "intensity": 0.5, "samples": 8, "casts_shadows": true}
      ],
      "materials": [
        {"name": "red", "diffuse": [0.7, 0.1, 0.1]},
        {"name": "glass", "ambient": [0, 0, 0], "specular": [1, 1, 1], "specular_exponent": 200,
         "refractive_index": 1.5, "reflectivity": 0.1, "transmissivity": 0.85,
         "use_point_colors": false, "texture": "/tex/brick.png"}
      ],
      "models": [
        {"name": "bunny", "pool": "/data/bunny.pool", "material": "glass", "surface": "iso",
         "transform": {"translate": [1, 0, 0], "rotate_degrees": [0, 90, 0], "scale": 2}},
        {"source": "/data/teapot.bpt", "material": 0, "surface": "patches"}
      ],
      "environment": {"color": [0.2, 0.3, 0.4], "image": "/env/sky.hdr", "intensity": 2},
      "render": {"max_bounces": 6, "shadows": false, "reflections": false, "refractions": false,
                 "exposure": 1.5, "gamma": 2.4, "spp": 16, "path_tracing": true, "caustics": true,
                 "light_map": true}
    })";
    const Scene s = parse_scene(text, "t.json");
    EXPECT_EQ(s.camera.position, (Vec3{1, 2, 3}));
    EXPECT_EQ(s.camera.up, (Vec3{0, 0, 1}));
    EXPECT_EQ(s.camera.fov_y_degrees, 60.0);
    EXPECT_EQ(s.camera.width, 640u);
    EXPECT_EQ(s.camera.height, 480u);
    ASSERT_EQ(s.point_lights.size(), 1u);
    EXPECT_EQ(s.point_lights[0].color, (Color{1, 0.5f, 0.25f}));
    EXPECT_EQ(s.point_lights[0].intensity, 3.0f);
    EXPECT_FALSE(s.point_lights[0].casts_shadows);
    ASSERT_EQ(s.area_lights.size(), 1u);
    EXPECT_EQ(s.area_lights[0].corner, (Vec3{-1, 3, -1}));
    EXPECT_EQ(s.area_lights[0].edge_v, (Vec3{0, 0, 2}));
    EXPECT_EQ(s.area_lights[0].samples, 8u);
    ASSERT_EQ(s.materials.size(), 2u);  // no default added when materials are given
    EXPECT_EQ(s.materials[0].name, "red");
    EXPECT_EQ(s.materials[0].diffuse_reflectance, 1.0f);  // 1 - 0 - 0
    EXPECT_EQ(s.materials[1].refractive_index, 1.5f);
    EXPECT_EQ(s.materials[1].specular_exponent, 200.0f);
    EXPECT_EQ(s.materials[1].point_colors, PointColors::none);  // use_point_colors false
    EXPECT_EQ(s.materials[0].point_colors, PointColors::automatic);
    EXPECT_FALSE(s.materials[0].intensity_range.has_value());
    EXPECT_EQ(s.materials[1].texture, "/tex/brick.png");
    // diffuse_reflectance not given: what reflectivity and transmissivity leave, 1 - 0.1 - 0.85.
    EXPECT_NEAR(s.materials[1].diffuse_reflectance, 0.05, 1e-6);
    ASSERT_EQ(s.models.size(), 2u);
    EXPECT_EQ(s.models[0].name, "bunny");
    EXPECT_EQ(s.models[0].pool, fs::path("/data/bunny.pool"));
    EXPECT_EQ(s.models[0].material, 1u);  // "glass" by name
    EXPECT_EQ(s.models[0].surface, SurfaceKind::iso);
    EXPECT_EQ(s.models[0].transform.rotate_degrees, (Vec3{0, 90, 0}));
    EXPECT_EQ(s.models[0].transform.scale, 2.0);
    EXPECT_EQ(s.models[1].name, "teapot");  // default: the file's stem
    EXPECT_TRUE(s.models[1].pool.empty());
    EXPECT_EQ(s.models[1].source, fs::path("/data/teapot.bpt"));
    EXPECT_EQ(s.models[1].material, 0u);
    EXPECT_EQ(s.models[1].surface, SurfaceKind::patches);
    EXPECT_EQ(s.environment.image, fs::path("/env/sky.hdr"));
    EXPECT_EQ(s.environment.intensity, 2.0f);
    EXPECT_EQ(s.render.max_bounces, 6u);
    EXPECT_FALSE(s.render.shadows);
    EXPECT_EQ(s.render.gamma, 2.4f);
    EXPECT_EQ(s.render.spp, 16u);
    EXPECT_TRUE(s.render.path_tracing);
    EXPECT_TRUE(s.render.light_map);
}

namespace {

void expect_same(const Scene& a, const Scene& b) {
    EXPECT_EQ(a.camera.position, b.camera.position);
    EXPECT_EQ(a.camera.look_at, b.camera.look_at);
    EXPECT_EQ(a.camera.up, b.camera.up);
    EXPECT_EQ(a.camera.fov_y_degrees, b.camera.fov_y_degrees);
    EXPECT_EQ(a.camera.width, b.camera.width);
    EXPECT_EQ(a.camera.height, b.camera.height);
    ASSERT_EQ(a.point_lights.size(), b.point_lights.size());
    for (std::size_t i = 0; i < a.point_lights.size(); ++i) {
        EXPECT_EQ(a.point_lights[i].position, b.point_lights[i].position);
        EXPECT_EQ(a.point_lights[i].color, b.point_lights[i].color);
        EXPECT_EQ(a.point_lights[i].intensity, b.point_lights[i].intensity);
        EXPECT_EQ(a.point_lights[i].casts_shadows, b.point_lights[i].casts_shadows);
    }
    ASSERT_EQ(a.area_lights.size(), b.area_lights.size());
    for (std::size_t i = 0; i < a.area_lights.size(); ++i) {
        EXPECT_EQ(a.area_lights[i].corner, b.area_lights[i].corner);
        EXPECT_EQ(a.area_lights[i].edge_u, b.area_lights[i].edge_u);
        EXPECT_EQ(a.area_lights[i].edge_v, b.area_lights[i].edge_v);
        EXPECT_EQ(a.area_lights[i].color, b.area_lights[i].color);
        EXPECT_EQ(a.area_lights[i].intensity, b.area_lights[i].intensity);
        EXPECT_EQ(a.area_lights[i].samples, b.area_lights[i].samples);
        EXPECT_EQ(a.area_lights[i].casts_shadows, b.area_lights[i].casts_shadows);
    }
    ASSERT_EQ(a.materials.size(), b.materials.size());
    for (std::size_t i = 0; i < a.materials.size(); ++i) {
        const Material& x = a.materials[i];
        const Material& y = b.materials[i];
        EXPECT_EQ(x.name, y.name);
        EXPECT_EQ(x.ambient, y.ambient);
        EXPECT_EQ(x.diffuse, y.diffuse);
        EXPECT_EQ(x.specular, y.specular);
        EXPECT_EQ(x.specular_exponent, y.specular_exponent);
        EXPECT_EQ(x.refractive_index, y.refractive_index);
        EXPECT_EQ(x.reflectivity, y.reflectivity);
        EXPECT_EQ(x.transmissivity, y.transmissivity);
        EXPECT_EQ(x.diffuse_reflectance, y.diffuse_reflectance);
        EXPECT_EQ(x.point_colors, y.point_colors);
        EXPECT_EQ(x.intensity_range, y.intensity_range);
        EXPECT_EQ(x.texture, y.texture);
    }
    ASSERT_EQ(a.models.size(), b.models.size());
    for (std::size_t i = 0; i < a.models.size(); ++i) {
        const Model& x = a.models[i];
        const Model& y = b.models[i];
        EXPECT_EQ(x.name, y.name);
        EXPECT_EQ(x.pool, y.pool);
        EXPECT_EQ(x.source, y.source);
        EXPECT_EQ(x.transform.translate, y.transform.translate);
        EXPECT_EQ(x.transform.rotate_degrees, y.transform.rotate_degrees);
        EXPECT_EQ(x.transform.scale, y.transform.scale);
        EXPECT_EQ(x.material, y.material);
        EXPECT_EQ(x.surface, y.surface);
    }
    EXPECT_EQ(a.environment.color, b.environment.color);
    EXPECT_EQ(a.environment.image, b.environment.image);
    EXPECT_EQ(a.environment.intensity, b.environment.intensity);
    EXPECT_EQ(a.render.max_bounces, b.render.max_bounces);
    EXPECT_EQ(a.render.shadows, b.render.shadows);
    EXPECT_EQ(a.render.reflections, b.render.reflections);
    EXPECT_EQ(a.render.refractions, b.render.refractions);
    EXPECT_EQ(a.render.exposure, b.render.exposure);
    EXPECT_EQ(a.render.gamma, b.render.gamma);
    EXPECT_EQ(a.render.spp, b.render.spp);
    EXPECT_EQ(a.render.path_tracing, b.render.path_tracing);
    EXPECT_EQ(a.render.caustics, b.render.caustics);
    EXPECT_EQ(a.render.light_map, b.render.light_map);
}

}  // namespace

TEST(Scene, RoundTripKeepsEveryValueExactly) {
    Scene s;
    s.camera.position = {0.1, -2.5e6, 1.0 / 3.0};  // values with no short decimal form
    s.camera.look_at = {1e-7, 2, 3};
    s.camera.up = {0, 0, 1};
    s.camera.fov_y_degrees = 179.5;
    s.camera.width = 16384;
    s.camera.height = 1;
    s.point_lights.push_back({{1, 2, 3}, {0.1f, 0.2f, 0.3f}, 7.25f, false});
    s.point_lights.push_back({{-1, -2, -3}, {10, 20, 30}, 0.0f, true});
    s.area_lights.push_back({{0, 5, 0}, {0.3, 0, 0}, {0, 0.7, 0.1}, {1, 1, 0.9f}, 1.0f / 3.0f, 64, false});
    Material glass;
    glass.name = "glass";
    glass.ambient = {0.01f, 0.02f, 0.03f};
    glass.diffuse = {0.1f, 0.2f, 0.3f};
    glass.specular = {1, 1, 1};
    glass.specular_exponent = 123.456f;
    glass.refractive_index = 1.52f;
    glass.reflectivity = 0.1f;
    glass.transmissivity = 0.8f;
    glass.diffuse_reflectance = 0.1f;
    glass.point_colors = PointColors::intensity;
    glass.intensity_range = std::array<float, 2>{0.1f, 1.0f / 3.0f};
    glass.texture = "/textures/a b.png";
    Material unnamed;  // no name: must be referenced by index
    unnamed.diffuse_reflectance = 0.25f;
    s.materials = {unnamed, glass};
    Model m1;
    m1.name = "bunny";
    m1.pool = "/models/bunny.pool";
    m1.transform = {{1, 2, 3}, {10, 20, 30}, 0.5};
    m1.material = 1;
    m1.surface = SurfaceKind::mls;
    Model m2;
    m2.name = "teapot";
    m2.source = "relative/teapot.bpt";
    m2.pool = "relative/teapot.pool";
    m2.material = 0;
    m2.surface = SurfaceKind::patches;
    s.models = {m1, m2};
    s.environment = {{0.5f, 0.25f, 0.125f}, "/env/sky.exr", 3.5f};
    s.render = {9, false, true, false, 0.75f, 1.8f, 256, true, true, false};

    const std::string text = to_json(s);
    // Relative paths stay relative when no base folder is given.
    const Scene back = parse_scene(text, "roundtrip.json");
    expect_same(s, back);
    // And a second trip gives the same text.
    EXPECT_EQ(to_json(back), text);
    // Material references: by name where the name is unique, by index where the material has none.
    EXPECT_NE(text.find("\"material\": \"glass\""), std::string::npos) << text;
    EXPECT_NE(text.find("\"material\": 0"), std::string::npos) << text;
}

TEST(Scene, RoundTripOfDefaults) {
    const Scene s = parse_scene("{}", "t.json");
    expect_same(s, parse_scene(to_json(s), "t.json"));
}

TEST(Scene, SurfaceNamesAreTheOnesSceneMdLists) {
    // SCENE.md models[].surface: "splats", "iso", "mls", "patches", in the enum's order (the
    // core's KernelMask bits are 1 << SurfaceKind).
    const char* documented[] = {"splats", "iso", "mls", "patches"};
    ASSERT_EQ(k_surface_kind_count, 4u);
    for (std::uint32_t i = 0; i < 4; ++i) {
        SurfaceKind k = SurfaceKind::splats;
        ASSERT_TRUE(parse_surface(documented[i], k)) << documented[i];
        EXPECT_EQ(static_cast<std::uint32_t>(k), i);
        EXPECT_EQ(surface_name(k), documented[i]);
    }
    for (const char* bad : {"", "Splats", "iso ", "voxels", "auto"}) {
        SurfaceKind k = SurfaceKind::mls;
        EXPECT_FALSE(parse_surface(bad, k)) << bad;
        EXPECT_EQ(k, SurfaceKind::mls) << "unchanged on failure";
    }
    EXPECT_EQ(std::string(k_surface_name_list), "splats, iso, mls or patches");
}

TEST(Scene, MaterialReferences) {
    const std::string mats = R"("materials": [{"name": "a"}, {"name": "b"}, {}])";
    EXPECT_EQ(parse_scene("{" + mats + R"(, "models": [{"pool": "/x.pool", "material": "b"}]})", "t")
                  .models[0]
                  .material,
              1u);
    EXPECT_EQ(parse_scene("{" + mats + R"(, "models": [{"pool": "/x.pool", "material": 2}]})", "t")
                  .models[0]
                  .material,
              2u);
    EXPECT_EQ(parse_scene("{" + mats + R"(, "models": [{"pool": "/x.pool"}]})", "t").models[0].material, 0u);
    // Without a materials list the default material is index 0 and is called "default".
    EXPECT_EQ(
        parse_scene(R"({"models": [{"pool": "/x.pool", "material": "default"}]})", "t").models[0].material,
        0u);
}

TEST(Scene, DiffuseReflectanceDefaultsToWhatIsLeft) {
    const Scene s = parse_scene(R"({"materials": [{"reflectivity": 0.25, "transmissivity": 0.5},
                                                   {"reflectivity": 1}, {"diffuse_reflectance": 0.3}]})",
                                "t");
    EXPECT_FLOAT_EQ(s.materials[0].diffuse_reflectance, 0.25f);
    EXPECT_FLOAT_EQ(s.materials[1].diffuse_reflectance, 0.0f);
    EXPECT_FLOAT_EQ(s.materials[2].diffuse_reflectance, 0.3f);  // absorbs 70 %
    // The sum may exceed 1 by rounding only (1e-6).
    EXPECT_NO_THROW(parse_scene(R"({"materials": [{"reflectivity": 0.3, "transmissivity": 0.3,
                                                   "diffuse_reflectance": 0.4000001}]})",
                                "t"));
}

struct ErrorCase {
    const char* json;
    const char* path;  ///< the JSON pointer the message must name
    const char* what;  ///< a fragment of the explanation
};

class SceneErrors : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(SceneErrors, NamesTheJsonPath) {
    const ErrorCase& c = GetParam();
    const std::string message = error_of(c.json);
    ASSERT_FALSE(message.empty()) << "accepted: " << c.json;
    const std::string prefix = std::string("t.json: ") + c.path + ": ";
    EXPECT_EQ(message.rfind(prefix, 0), 0u) << "message: " << message << "\nexpected prefix: " << prefix;
    EXPECT_NE(message.find(c.what), std::string::npos) << "message: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    Strict, SceneErrors,
    ::testing::Values(
        ErrorCase{"[]", "(document)", "expected an object"},
        ErrorCase{R"({"camra": {}})", "/camra", "unknown key"},
        ErrorCase{R"({"camera": {"fov": 40}})", "/camera/fov", "unknown key"},
        ErrorCase{R"({"camera": []})", "/camera", "expected an object"},
        ErrorCase{R"({"camera": {"fov_y_degrees": -1}})", "/camera/fov_y_degrees", "(0, 180)"},
        ErrorCase{R"({"camera": {"fov_y_degrees": 0}})", "/camera/fov_y_degrees", "(0, 180)"},
        ErrorCase{R"({"camera": {"fov_y_degrees": 180}})", "/camera/fov_y_degrees", "(0, 180)"},
        ErrorCase{R"({"camera": {"fov_y_degrees": "wide"}})", "/camera/fov_y_degrees", "expected a number"},
        ErrorCase{R"({"camera": {"width": 0}})", "/camera/width", "[1, 16384]"},
        ErrorCase{R"({"camera": {"height": 16385}})", "/camera/height", "[1, 16384]"},
        ErrorCase{R"({"camera": {"width": -5}})", "/camera/width", "got -5"},
        ErrorCase{R"({"camera": {"width": 512.5}})", "/camera/width", "expected an integer"},
        ErrorCase{R"({"camera": {"position": [1, 2]}})", "/camera/position", "array of 3"},
        ErrorCase{R"({"camera": {"position": [1, "2", 3]}})", "/camera/position/1", "expected a number"},
        ErrorCase{R"({"camera": {"position": [0, 0, 0]}})", "/camera/look_at", "equals the camera position"},
        ErrorCase{R"({"camera": {"up": [0, 0, 0]}})", "/camera/up", "zero vector"},
        ErrorCase{R"({"camera": {"up": [0, 0, -2]}})", "/camera/up", "parallel"},
        ErrorCase{R"({"lights": {}})", "/lights", "expected an array"},
        ErrorCase{R"({"lights": [{"position": [0, 1, 0]}]})", "/lights/0", "missing key \"type\""},
        ErrorCase{R"({"lights": [{"type": "spot"}]})", "/lights/0/type", "unknown light type"},
        ErrorCase{R"({"lights": [{"type": "point"}, {"type": "point", "samples": 4}]})", "/lights/1/samples",
                  "unknown key"},
        ErrorCase{R"({"lights": [{"type": "point", "intensity": -1}]})", "/lights/0/intensity", ">= 0"},
        ErrorCase{R"({"lights": [{"type": "point", "color": [1, -0.5, 1]}]})", "/lights/0/color/1", ">= 0"},
        ErrorCase{R"({"lights": [{"type": "point", "casts_shadows": 1}]})", "/lights/0/casts_shadows",
                  "expected true or false"},
        ErrorCase{R"({"lights": [{"type": "area", "samples": 0}]})", "/lights/0/samples", "[1, 64]"},
        ErrorCase{R"({"lights": [{"type": "area", "edge_u": [0, 0, 0]}]})", "/lights/0/edge_u",
                  "zero vector"},
        ErrorCase{R"({"lights": [{"type": "area", "edge_u": [1, 0, 0], "edge_v": [-3, 0, 0]}]})",
                  "/lights/0/edge_v", "parallel"},
        ErrorCase{
            R"({"materials": [{}, {"reflectivity": 0.6, "transmissivity": 0.3, "diffuse_reflectance": 0.2}]})",
            "/materials/1/diffuse_reflectance", "exceeds 1"},
        ErrorCase{R"({"materials": [{"reflectivity": 0.6, "transmissivity": 0.5}]})",
                  "/materials/0/transmissivity", "exceeds 1"},
        ErrorCase{R"({"materials": [{"reflectivity": 1.5}]})", "/materials/0/reflectivity", "[0, 1]"},
        ErrorCase{R"({"materials": [{"transmissivity": -0.1}]})", "/materials/0/transmissivity", "[0, 1]"},
        ErrorCase{R"({"materials": [{"refractive_index": 0.9}]})", "/materials/0/refractive_index", ">= 1"},
        ErrorCase{R"({"materials": [{"specular_exponent": -2}]})", "/materials/0/specular_exponent", ">= 0"},
        ErrorCase{R"({"materials": [{"diffuse": [0.5, 1.2, 0.5]}]})", "/materials/0/diffuse/1", "[0, 1]"},
        ErrorCase{R"({"materials": [{"name": "a"}, {"name": "a"}]})", "/materials/1/name",
                  "duplicate material"},
        ErrorCase{R"({"materials": [{"texture": ""}]})", "/materials/0/texture", "empty"},
        ErrorCase{R"({"materials": [{"colour": [1, 1, 1]}]})", "/materials/0/colour", "unknown key"},
        ErrorCase{R"({"materials": [{"name": "a"}], "models": [{"pool": "/m.pool", "material": "b"}]})",
                  "/models/0/material", "no material named \"b\""},
        ErrorCase{R"({"materials": [{"name": "a"}], "models": [{"pool": "/m.pool", "material": 1}]})",
                  "/models/0/material", "out of range"},
        ErrorCase{R"({"models": [{"pool": "/m.pool", "material": -1}]})", "/models/0/material",
                  "out of range"},
        ErrorCase{R"({"models": [{"pool": "/m.pool", "material": 0.5}]})", "/models/0/material",
                  "material name (string) or index"},
        ErrorCase{R"({"models": [{"pool": "/m.pool"}, {"name": "x"}]})", "/models/1", "needs \"pool\""},
        ErrorCase{R"({"models": [{"pool": 3}]})", "/models/0/pool", "expected a string"},
        ErrorCase{R"({"models": [{"pool": "/m.pool", "surface": "voxels"}]})", "/models/0/surface",
                  "unknown surface"},
        ErrorCase{R"({"models": [{"pool": "/m.pool", "transform": {"scale": 0}}]})",
                  "/models/0/transform/scale", "> 0"},
        ErrorCase{R"({"models": [{"pool": "/m.pool", "transform": {"rotate": [0, 0, 0]}}]})",
                  "/models/0/transform/rotate", "unknown key"},
        ErrorCase{R"({"environment": {"intensity": -1}})", "/environment/intensity", ">= 0"},
        ErrorCase{R"({"environment": {"image": ""}})", "/environment/image", "empty"},
        ErrorCase{R"({"render": {"max_bounces": 65}})", "/render/max_bounces", "[0, 64]"},
        ErrorCase{R"({"render": {"spp": 0}})", "/render/spp", "[1, 65536]"},
        ErrorCase{R"({"render": {"gamma": 0}})", "/render/gamma", "> 0"},
        ErrorCase{R"({"render": {"exposure": -1}})", "/render/exposure", "> 0"},
        ErrorCase{R"({"render": {"caustics": "yes"}})", "/render/caustics", "expected true or false"},
        ErrorCase{R"({"render": {"shadows": true, "shadows": false}})", "/render/shadows", "duplicate key"},
        ErrorCase{R"({"materials": [{}, {"name": "x", "name": "y"}]})", "/materials/1/name", "duplicate key"},
        ErrorCase{R"({"camera": {"position": [0, 1e999, 0]}})", "/camera/position/1", "number overflow"},
        ErrorCase{R"({"a/b~c": 1})", "/a~1b~0c", "unknown key"},
        // point_colors, use_point_colors and intensity_range (SCENE.md, materials)
        ErrorCase{R"({"materials": [{"point_colors": "rgb"}]})", "/materials/0/point_colors",
                  "unknown value \"rgb\" (expected auto, colors, intensity or none)"},
        ErrorCase{R"({"materials": [{"point_colors": true}]})", "/materials/0/point_colors",
                  "expected a string"},
        ErrorCase{R"({"materials": [{"point_colors": "none", "use_point_colors": false}]})",
                  "/materials/0/use_point_colors", "not both"},
        ErrorCase{R"({"materials": [{"use_point_colors": "colors"}]})", "/materials/0/use_point_colors",
                  "expected true or false"},
        ErrorCase{R"({"materials": [{"intensity_range": [0, 1, 2]}]})", "/materials/0/intensity_range",
                  "array of 2"},
        ErrorCase{R"({"materials": [{"intensity_range": 5}]})", "/materials/0/intensity_range",
                  "expected [lo, hi]"},
        ErrorCase{R"({"materials": [{"intensity_range": [0, "1"]}]})", "/materials/0/intensity_range/1",
                  "expected a number"},
        ErrorCase{R"({"materials": [{"intensity_range": [2, 2]}]})", "/materials/0/intensity_range/1",
                  "greater than lo"},
        ErrorCase{R"({"materials": [{"intensity_range": [3, -1]}]})", "/materials/0/intensity_range/1",
                  "greater than lo"},
        ErrorCase{R"({"materials": [{"intensity_range": [0, 1e39]}]})", "/materials/0/intensity_range/1",
                  "32-bit float"}));

TEST(Scene, PointColorsAndItsOlderBooleanForm) {
    const Scene s = parse_scene(R"({"materials": [{}, {"point_colors": "auto"}, {"point_colors": "colors"},
        {"point_colors": "intensity", "intensity_range": [-2.5, 40]}, {"point_colors": "none"},
        {"use_point_colors": true}, {"use_point_colors": false}, {"intensity_range": [0, 1]}]})",
                                "t");
    ASSERT_EQ(s.materials.size(), 8u);
    EXPECT_EQ(s.materials[0].point_colors, PointColors::automatic);  // SCENE.md default: auto
    EXPECT_EQ(s.materials[1].point_colors, PointColors::automatic);
    EXPECT_EQ(s.materials[2].point_colors, PointColors::colors);
    EXPECT_EQ(s.materials[3].point_colors, PointColors::intensity);
    ASSERT_TRUE(s.materials[3].intensity_range.has_value());
    EXPECT_EQ(*s.materials[3].intensity_range, (std::array<float, 2>{-2.5f, 40.0f}));
    EXPECT_EQ(s.materials[4].point_colors, PointColors::none);
    EXPECT_EQ(s.materials[5].point_colors, PointColors::colors);  // true: the pool's colors
    EXPECT_EQ(s.materials[6].point_colors, PointColors::none);    // false: none
    EXPECT_EQ(s.materials[7].point_colors, PointColors::automatic);
    EXPECT_TRUE(s.materials[7].intensity_range.has_value());
    // Written back as point_colors (never the older key), and read back the same.
    const std::string text = to_json(s);
    EXPECT_EQ(text.find("use_point_colors"), std::string::npos) << text;
    const Scene t = parse_scene(text, "t2");
    for (std::size_t i = 0; i < s.materials.size(); ++i) {
        EXPECT_EQ(t.materials[i].point_colors, s.materials[i].point_colors) << i;
        EXPECT_EQ(t.materials[i].intensity_range, s.materials[i].intensity_range) << i;
    }
}

TEST(Scene, IntensityRangeIsTheFirstAndNinetyNinthPercentile) {
    // 0, 1, ..., 200 shuffled: nearest rank round(0.01 * 200) = 2 and round(0.99 * 200) = 198.
    std::vector<float> v;
    for (int i = 0; i <= 200; ++i) v.push_back(static_cast<float>((i * 37) % 201));
    v.push_back(std::numeric_limits<float>::quiet_NaN());  // non-finite values are left out
    v.push_back(std::numeric_limits<float>::infinity());
    const auto r = intensity_range(v);
    EXPECT_EQ(r[0], 2.0f);
    EXPECT_EQ(r[1], 198.0f);
    EXPECT_EQ(intensity_range(std::vector<float>{}), (std::array<float, 2>{0.0f, 0.0f}));
    EXPECT_EQ(intensity_range(std::vector<float>{7.0f}), (std::array<float, 2>{7.0f, 7.0f}));
}

TEST(Scene, IntensityGreyIsLinearInTheRangeAndSrgbEncoded) {
    // sRGB decode of the byte gives back t = (I - lo) / (hi - lo) (IEC 61966-2-1), to 8-bit rounding.
    auto decode = [](std::uint8_t b) {
        const double c = b / 255.0;
        return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    };
    for (int i = 0; i <= 10; ++i) {
        const float intensity = 100.0f + 30.0f * static_cast<float>(i);  // lo 100, hi 400
        EXPECT_NEAR(decode(intensity_grey(intensity, 100.0f, 400.0f)), i / 10.0, 0.01) << intensity;
    }
    EXPECT_EQ(intensity_grey(-1e6f, 100.0f, 400.0f), 0);  // clamped
    EXPECT_EQ(intensity_grey(1e6f, 100.0f, 400.0f), 255);
    EXPECT_EQ(intensity_grey(5.0f, 3.0f, 3.0f), 255);  // no range: white
    EXPECT_EQ(intensity_grey(std::numeric_limits<float>::quiet_NaN(), 0.0f, 1.0f), 0);
}

TEST(Scene, InvalidJsonNamesTheLine) {
    const std::string message = error_of("{\n  \"camera\": {\n    \"width\": 5,\n  }\n}");
    EXPECT_EQ(message.rfind("t.json: invalid JSON: ", 0), 0u) << message;
    EXPECT_NE(message.find("line 4"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(error_of("").find("invalid JSON"), std::string::npos);
}

TEST(Scene, RelativePathsResolveAgainstTheSceneFolder) {
    TempDir dir;
    const fs::path file = dir.path() / "scenes" / "room.json";
    write_file(file, R"({
      "materials": [{"name": "brick", "texture": "../textures/brick.png"}],
      "models": [{"pool": "models/room.pool", "source": "/abs/room.ply"},
                 {"source": "../scans/bunny.ply"}],
      "environment": {"image": "sky.hdr"}
    })");
    const Scene s = load_scene(file);
    EXPECT_EQ(s.file, file);
    const fs::path scenes = dir.path() / "scenes";
    EXPECT_EQ(s.models[0].pool, scenes / "models" / "room.pool");
    EXPECT_EQ(s.models[0].source, fs::path("/abs/room.ply"));  // absolute paths are kept
    EXPECT_EQ(s.models[1].source, dir.path() / "scans" / "bunny.ply");
    EXPECT_EQ(s.models[1].name, "bunny");
    EXPECT_EQ(fs::path(s.materials[0].texture), dir.path() / "textures" / "brick.png");
    EXPECT_EQ(s.environment.image, scenes / "sky.hdr");

    // A scene file given by a relative path resolves against its folder too, not the working folder.
    const fs::path cwd = fs::current_path();
    fs::current_path(dir.path());
    Scene relative;
    EXPECT_NO_THROW(relative = load_scene("scenes/room.json"));
    fs::current_path(cwd);
    EXPECT_EQ(relative.models[0].pool, scenes / "models" / "room.pool");

    // parse_scene with a base folder does the same.
    const Scene p = parse_scene(R"({"models": [{"pool": "a/../b.pool"}]})", "x", "/base/dir");
    EXPECT_EQ(p.models[0].pool, fs::path("/base/dir/b.pool"));
}

TEST(Scene, LoadErrorsNameTheFile) {
    TempDir dir;
    const fs::path missing = dir.path() / "nope.json";
    try {
        load_scene(missing);
        FAIL() << "no error for a missing file";
    } catch (const prt::Error& e) {
        EXPECT_EQ(std::string(e.what()).rfind(missing.string() + ": ", 0), 0u) << e.what();
    }
    const fs::path bad = dir.path() / "bad.json";
    write_file(bad, R"({"render": {"spp": 0}})");
    try {
        load_scene(bad);
        FAIL() << "no error for spp 0";
    } catch (const prt::Error& e) {
        EXPECT_EQ(std::string(e.what()).rfind(bad.string() + ": /render/spp: ", 0), 0u) << e.what();
    }
}

TEST(Scene, TheExampleInSceneMdParses) {
    // SCENE.md's complete example must stay valid: extract its ```json block.
    std::ifstream in(fs::path(PRT_SOURCE_DIR) / "formats" / "SCENE.md");
    ASSERT_TRUE(in) << "formats/SCENE.md not found under " << PRT_SOURCE_DIR;
    std::stringstream doc;
    doc << in.rdbuf();
    const std::string text = doc.str();
    const std::string open = "```json\n";
    const auto begin = text.find(open);
    ASSERT_NE(begin, std::string::npos) << "no ```json block in SCENE.md";
    const auto end = text.find("```", begin + open.size());
    ASSERT_NE(end, std::string::npos);
    const std::string example = text.substr(begin + open.size(), end - begin - open.size());
    Scene s;
    ASSERT_NO_THROW(s = parse_scene(example, "SCENE.md example", "/scenes")) << error_of(example, "/scenes");
    EXPECT_FALSE(s.models.empty());
    EXPECT_FALSE(s.point_lights.empty());
    EXPECT_FALSE(s.area_lights.empty());
    EXPECT_GE(s.materials.size(), 2u);
}
