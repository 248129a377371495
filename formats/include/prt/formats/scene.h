// PointRT scene description: the JSON file (formats/SCENE.md) parsed into plain host structs.
// The runtime converts these into its device-side POD views; preprocess tools (photons, light maps,
// prt-bake) read them to decide which steps a scene needs.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "prt/error.h"
#include "prt/formats/scene_layout.h"
#include "prt/vec3.h"

namespace prt::scene {

using Vec3 = Vec3d;
using Color = std::array<float, 3>;  ///< linear RGB

struct Camera {
    Vec3 position{0, 0, 5};
    Vec3 look_at{0, 0, 0};
    Vec3 up{0, 1, 0};
    double fov_y_degrees = 45.0;  ///< vertical field of view
    std::uint32_t width = 512;
    std::uint32_t height = 512;
};

struct PointLight {
    Vec3 position{0, 10, 0};
    Color color{1, 1, 1};
    float intensity = 1.0f;   ///< multiplies color
    bool casts_shadows = true;
};

/// A rectangular area light: corner + two edge vectors; rendered as samples x samples point
/// lights (seed 002, 5.6) or sampled in path tracing.
struct AreaLight {
    Vec3 corner{-0.5, 5, -0.5};
    Vec3 edge_u{1, 0, 0};
    Vec3 edge_v{0, 0, 1};
    Color color{1, 1, 1};
    float intensity = 1.0f;
    std::uint32_t samples = 4;  ///< per edge
    bool casts_shadows = true;
};

/// What multiplies a material's diffuse color point by point (SCENE.md, materials[].point_colors).
enum class PointColors {
    automatic,  ///< "auto": the pool's colors, else its intensities, else nothing
    colors,     ///< the pool's per-point colors (nothing when it has none)
    intensity,  ///< the pool's scanner intensities as a grey level (nothing when it has none)
    none,       ///< nothing: the diffuse color alone
};

/// The thesis's material model (5.1): eight properties.
struct Material {
    std::string name;
    Color ambient{0.05f, 0.05f, 0.05f};
    Color diffuse{0.8f, 0.8f, 0.8f};
    Color specular{0.2f, 0.2f, 0.2f};
    float specular_exponent = 32.0f;
    float refractive_index = 1.0f;
    float reflectivity = 0.0f;       ///< fraction perfectly reflected
    float transmissivity = 0.0f;     ///< fraction transmitted (refracted)
    float diffuse_reflectance = 1.0f;///< fraction contributing to local shading
    PointColors point_colors = PointColors::automatic;  ///< what modulates diffuse per point
    /// point_colors intensity: this range maps to grey 0..1 (lo < hi); unset: the 1st and 99th
    /// percentiles of each pool's intensities (intensity_range() below).
    std::optional<std::array<float, 2>> intensity_range;
    std::string texture;             ///< optional tri-planar texture image (prt-texture)
};

struct Transform {
    Vec3 translate{0, 0, 0};
    Vec3 rotate_degrees{0, 0, 0};  ///< applied X, then Y, then Z
    double scale = 1.0;
};

struct Model {
    std::string name;
    std::filesystem::path pool;    ///< a .pool file (resolved relative to the scene file)
    std::filesystem::path source;  ///< or a source file (PLY/...); prt-bake imports it
    Transform transform;
    std::uint32_t material = 0;    ///< index into Scene::materials
    SurfaceKind surface = SurfaceKind::splats;  ///< scene_layout.h
};

struct Environment {
    Color color{0.1f, 0.1f, 0.15f};  ///< background when no image
    std::filesystem::path image;     ///< optional latitude-longitude HDR image
    float intensity = 1.0f;
};

struct RenderSettings {
    std::uint32_t max_bounces = 4;  ///< reflection/refraction depth
    bool shadows = true;
    bool reflections = true;
    bool refractions = true;
    float exposure = 1.0f;          ///< tone mapping
    float gamma = 2.2f;
    std::uint32_t spp = 1;          ///< samples per pixel (path tracing)
    bool path_tracing = false;
    bool caustics = false;          ///< ask for a photon pass (prt-bake)
    bool light_map = false;         ///< ask for a light-map bake (prt-bake)
};

struct Scene {
    std::filesystem::path file;  ///< the scene file this came from (empty if built in code)
    Camera camera;
    std::vector<PointLight> point_lights;
    std::vector<AreaLight> area_lights;
    std::vector<Material> materials;  ///< at least one (a default is added when none is given)
    std::vector<Model> models;
    Environment environment;
    RenderSettings render;
};

/// Parses a scene file. Unknown keys, wrong types and out-of-range values throw prt::Error
/// "FILE: JSON_PATH: what" (for example "room.json: /materials/2/reflectivity: expected a number").
/// Relative paths inside the scene are resolved against the scene file's folder.
Scene load_scene(const std::filesystem::path& file);
/// Parses scene JSON text; `label` names it in errors; relative paths resolve against `base_dir`.
Scene parse_scene(const std::string& json_text, const std::string& label,
                  const std::filesystem::path& base_dir = {});
/// Serializes a scene back to JSON text (round trip with parse_scene).
std::string to_json(const Scene& scene);

/// The JSON name of a PointColors value ("auto", "colors", "intensity", "none").
const char* point_colors_name(PointColors p);
/// Parses "auto", "colors", "intensity" or "none"; false for anything else.
bool parse_point_colors(const std::string& text, PointColors& out);

/// SCENE.md's default intensity range: the 1st and 99th percentiles (nearest rank over the sorted
/// finite values) of a pool's intensities; {0, 0} when none is finite. lo == hi is possible.
std::array<float, 2> intensity_range(std::span<const float> intensities);
/// The grey level an intensity shades with, as an sRGB-encoded byte (point colors are stored
/// display-encoded): t = (intensity - lo) / (hi - lo) clamped to [0, 1] is the linear reflectance
/// factor, so radiance is proportional to t. hi <= lo gives 255 (white: nothing to tell apart);
/// a non-finite intensity gives 0.
std::uint8_t intensity_grey(float intensity, float lo, float hi);

}  // namespace prt::scene
