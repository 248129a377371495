// PointRT core: the scene as kernels see it: POD structs and non-owning views built on the host
// (runtime/host: RenderScene) from a scene file and memory-mapped pools.
//
// Frames: each model's pool stores positions in its local frame (ModelInfo::origin). Rendering
// happens in the "render frame": the world frame translated so that the first model's local
// origin is at zero. The host computes every offset in double before rounding to float, so a
// model 1e6 units from the world origin renders at full float precision (DESIGN.md).
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/octree.h"

namespace prt::core {

/// The thesis's material model (5.1): eight properties (+ whether point colors modulate it).
struct Material {
    Vec3 ambient{0.05f, 0.05f, 0.05f};
    Vec3 diffuse{0.8f, 0.8f, 0.8f};
    Vec3 specular{0.2f, 0.2f, 0.2f};
    float specular_exponent = 32.0f;
    float refractive_index = 1.0f;
    float reflectivity = 0.0f;         ///< fraction perfectly reflected
    float transmissivity = 0.0f;       ///< fraction refracted
    float diffuse_reflectance = 1.0f;  ///< fraction contributing to local (Lambert + Phong) shading
    std::uint32_t use_point_colors = 1;
};

/// thesis 5.2: a point light with a position, a color and a shadow flag.
struct PointLight {
    Vec3 position{0, 10, 0};  ///< render frame
    Vec3 color{1, 1, 1};      ///< linear RGB, intensity already multiplied in
    std::uint32_t casts_shadows = 1;
};

/// Background: a constant color, or a latitude-longitude image (linear RGB floats, row 0 = up).
struct EnvironmentView {
    Vec3 color{0.1f, 0.1f, 0.15f};
    float intensity = 1.0f;
    const float* image = nullptr;  ///< width * height * 3 floats, or null
    std::uint32_t width = 0, height = 0;
};

/// Tone-mapping operators applied before gamma for 8-bit output.
enum class ToneMap : std::uint32_t { clamp = 0, reinhard = 1, aces = 2 };

/// Hard limit on RenderParams::max_bounces (sizes the fixed ray stack of trace_ray()).
inline constexpr std::uint32_t k_max_bounces = 16;

/// Per-frame render settings.
struct RenderParams {
    std::uint32_t max_bounces = 4;  ///< reflection/refraction depth, clamped to k_max_bounces
    std::uint32_t shadows = 1;
    std::uint32_t reflections = 1;
    std::uint32_t refractions = 1;
    float exposure = 1.0f;
    float gamma = 2.2f;
    ToneMap tone_map = ToneMap::clamp;
    float blend_window = 1.0f;           ///< thesis 3.3: blending interval, in radii of the nearest splat
    std::uint32_t deep_blending = 0;     ///< thesis 3.5
    std::uint32_t max_steps = 1u << 16;  ///< leaves one ray may visit in one octree
    float min_ray_weight = 1e-3f;        ///< secondary rays carrying less intensity are not traced
    /// LeafCulling (splat.h): which per-leaf bounds tests may pass a filled leaf unread (they never
    /// change the image; 0 turns them off, for comparison).
    std::uint32_t leaf_culling = 2;
};

/// One model: its octree and per-point attributes, and its placement in the render frame:
/// render = rotation * (scale * local) + offset.
struct ModelView {
    OctreeView octree;
    const pool::Rgba8* colors = nullptr;          ///< per point, or null
    const std::uint32_t* material_ids = nullptr;  ///< per point, or null
    std::uint32_t point_count = 0;
    std::uint32_t material = 0;  ///< default material (Model::material)
    Mat3 rotation = mat3_identity();
    float scale = 1.0f;
    float inv_scale = 1.0f;
    Vec3 offset{0, 0, 0};
};

/// Everything a kernel needs to shade a frame.
struct SceneView {
    const ModelView* models = nullptr;
    std::uint32_t model_count = 0;
    const Material* materials = nullptr;  ///< at least one
    std::uint32_t material_count = 0;
    const PointLight* lights = nullptr;
    std::uint32_t light_count = 0;
    EnvironmentView environment;
    RenderParams params;
};

}  // namespace prt::core
