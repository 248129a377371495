// PointRT core: the scene as kernels see it: POD structs and non-owning views built on the host
// (runtime/host: RenderScene) from a scene file and memory-mapped pools.
//
// Frames: each model's pool stores positions in its local frame (ModelInfo::origin). Rendering
// happens in the "render frame": the world frame translated so that the first model's local
// origin is at zero. The host computes every offset in double before rounding to float, so a
// model 1e6 units from the world origin renders at full float precision (DESIGN.md).
#pragma once

#include <cstdint>

#include "prt/core/bricks.h"
#include "prt/core/gi.h"
#include "prt/core/iso.h"
#include "prt/core/math.h"
#include "prt/core/mls.h"
#include "prt/core/octree.h"
#include "prt/core/patch.h"
#include "prt/formats/scene_layout.h"

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

/// An area light (seed 002, 5.6): a parallelogram corner + s edge_u + t edge_v, s, t in [0, 1].
/// The ray tracer sees it as samples x samples point lights (RenderScene); the path tracer samples
/// it uniformly by area and sees its face (path.h).
struct AreaLight {
    Vec3 corner{0, 0, 0};  ///< render frame
    Vec3 edge_u{1, 0, 0};
    Vec3 edge_v{0, 0, 1};
    Vec3 color{1, 1, 1};  ///< linear RGB, total intensity already multiplied in
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
    float blend_window = 1.0f;  ///< thesis 3.3: blending interval, in radii of the nearest splat
    /// thesis 3.5; on by default since issue 15 (prt-fidelity, the ten bunny scans: depth error 0.28
    /// -> 0.18 spacings, false hits at silhouettes 0.70 % -> 0.43 %; the synthetic sphere's p99 hit
    /// error 3.7e-5 -> 2.3e-5 of the diagonal)
    std::uint32_t deep_blending = 1;
    std::uint32_t max_steps = 1u << 16;  ///< leaves one ray may visit in one octree
    float min_ray_weight = 1e-3f;        ///< secondary rays carrying less intensity are not traced
    /// LeafCulling (splat.h): which per-leaf bounds tests may pass a filled leaf unread (they never
    /// change the image; 0 turns them off, for comparison).
    std::uint32_t leaf_culling = 2;
    /// Level of detail (issue 17, bricks.h): a ray stops at a bricked model's node whose cell is at
    /// most this many pixels wide at the ray's distance and takes the node's disc. 0 (the core's
    /// default): never; prt-play and prt-bench default to 1.
    float lod_pixels = 0.0f;
    /// Set by the backends from the frame's camera: lod_pixels * pixel_angle(), and the camera's
    /// position (render frame). A ray's footprint t from its origin o is lod_spread * (|o - lod_eye|
    /// + t): 0 wide at the eye for camera rays; a ray leaving a hit starts with the pixel cone's
    /// width there (render.h lod_cone).
    float lod_spread = 0.0f;
    Vec3 lod_eye{0, 0, 0};
    /// seed 002, 7: path trace (path.h) instead of Whitted ray tracing; samples per pixel (both
    /// modes: stratified and jittered, so spp > 1 antialiases the ray tracer too); the depth at
    /// which a path gathers direct light and ends; the frame number (progressive accumulation:
    /// each frame draws new samples).
    std::uint32_t path_tracing = 0;
    std::uint32_t spp = 1;
    std::uint32_t max_path_depth = 10;
    std::uint32_t frame = 0;
    /// Intersection settings of the other surfaces (the accuracy knobs of issue 9). The renderer
    /// overrides their `faces` per ray (closest_hit_scene: the seamless rule of thesis 3.6).
    IsoParams iso;           ///< thesis 4.5: samples per leaf edge, refinement steps, seams
    MlsParams mls;           ///< WS05 3.2: samples per cell interval (k), refinement steps
    PatchTraceParams patch;  ///< seed 002, 3: Newton iteration cap, tolerance, domain margins
};

/// Which representation of a model rays meet: the scene file's own enum (prt/formats/scene_layout.h).
using scene::SurfaceKind;

/// One model: the view of the surface it is traced as, per-point attributes, and its placement in
/// the render frame: render = rotation * (scale * local) + offset. Only the view named by
/// `surface` is set; the others stay empty.
struct ModelView {
    SurfaceKind surface = SurfaceKind::splats;
    OctreeView octree;       ///< splats
    BrickView bricks;        ///< splats of a bricked pool (issue 17): traced instead of `octree` when set
    IsoView iso;             ///< iso
    MlsView mls;             ///< mls
    PatchView patches;       ///< patches
    CausticView caustics;    ///< prt-photons' caustic octree (thesis 5.4), or empty
    LightMapView light_map;  ///< prt-lightmap's diffuse light map (thesis 5.3), or empty
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
    const PointLight* lights = nullptr;  ///< point lights first, then the area lights' samples
    std::uint32_t light_count = 0;
    std::uint32_t point_light_count = 0;  ///< lights[0, point_light_count) are the scene's point lights
    const AreaLight* area_lights = nullptr;
    std::uint32_t area_light_count = 0;
    EnvironmentView environment;
    RenderParams params;
};

}  // namespace prt::core
