// PointRT runtime (host): a scene ready to render: pools mapped, scene-file materials, lights and
// camera converted into the core's POD views, in the render frame (prt/core/scene_view.h).
//
// The render frame is the world frame translated so that the first model's local origin
// (ModelInfo::origin after its transform) is at zero. All world-to-render conversions are done
// here in double and rounded to float once, so models far from the world origin keep full float
// precision (DESIGN.md, "The pool file" / numerical robustness).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "prt/core/camera.h"
#include "prt/core/scene_view.h"
#include "prt/formats/pool.h"
#include "prt/formats/scene.h"
#include "prt/runtime/image.h"
#include "prt/runtime/scan_frame.h"
#include "prt/vec3.h"

namespace prt::rt {

using DVec3 = Vec3d;

/// One model as loaded: its pool and the views into it.
struct LoadedModel {
    std::string name;
    std::shared_ptr<const pool::PoolFile> pool;
    core::ModelView view;  ///< pointers into the mapped pool (and leaf_bounds below)
    /// Per filled leaf: bounds that let rays pass it unread (derived at load, not in the pool).
    std::vector<core::LeafBounds> leaf_bounds;
    std::vector<core::NodeBox> node_boxes;    ///< the octree's internal nodes' (view.octree.node_boxes)
    std::vector<std::uint8_t> node_box_mask;  ///< view.octree.node_box_mask
    std::vector<core::MacroRegion> macro_regions;  ///< the empty leaves' (view.octree.macro_regions)
    std::vector<std::uint32_t> region_nodes;       ///< the node pool indexing them (view.octree.nodes)
    /// Bricked pools: per filled leaf of every brick, the compact bounds (core::BrickLeafBounds).
    std::vector<core::BrickLeafBounds> brick_leaf_bounds;
    /// Bricked pools: brick b's first leaf in brick_leaf_bounds (core::BrickView::leaf_bounds_first).
    std::vector<std::uint32_t> brick_leaf_first;
    /// Bricked pools loaded with LoadOptions::defer_bricks: only the index is validated (top tree,
    /// table, LOD), the payloads are not read and view.bricks has no leaf bounds yet (streaming,
    /// rt::BrickStream; or RenderScene::load_deferred_bricks for the in-core path).
    bool bricks_deferred = false;
    /// Per point: the colors the view shades with when they are not the pool's own (SCENE.md
    /// point_colors: intensities as grey levels, or a mix by material); empty otherwise.
    std::vector<pool::Rgba8> shading_colors;
    DVec3 world_min, world_max;  ///< bounds after the model's transform (world frame)
    std::uint64_t bytes = 0;     ///< bytes of the sections the renderer reads, leaf bounds included
};

/// LoadOptions::empty_space's default.
inline constexpr const char* k_default_empty_space = "regions";

/// How models are loaded (override the scene file).
struct LoadOptions {
    /// Surface of every model: "" keeps each model's (SCENE.md models[].surface), "auto" takes what
    /// each pool holds (splats, else patches, ISO, MLS), or one of splats, iso, mls, patches.
    std::string surface;
    /// ISO: trace the float leaves (160 B) instead of the quantized ones (56 B) when a pool has both.
    bool iso_float = false;
    /// Splats: trace the bricks (prt-bricks) of a pool that also kept its float octree
    /// (--keep-float); a pool with bricks only always traces them.
    bool bricks = false;
    /// Bricked models: validate only the brick index (pool::validate_brick_index) and leave the
    /// payloads unread, for rt::BrickStream to stream them or load them all (in core).
    bool defer_bricks = false;
    /// Splat octrees and ISOs: how the walk passes empty space: "regions" (macro-regions; ISOs too),
    /// "boxes" (node boxes; splats only), "both", "none", or "" (k_default_empty_space;
    /// runtime/README.md). The image is the same.
    std::string empty_space;
    /// Replaces every material's point_colors (SCENE.md; prt-play --point-colors) when set.
    std::optional<scene::PointColors> point_colors;
};

/// Options that override the scene file.
struct SceneOverrides {
    std::uint32_t width = 0, height = 0;  ///< 0: keep
};

class RenderScene {
public:
    /// Loads a scene file's models (their pools must hold the octree sections: prt-octree).
    /// `pool_override`, when not empty, replaces the scene's models by this one pool (keeping the
    /// first model's transform and material if the scene has models). Throws prt::Error naming
    /// the file and what is wrong.
    /// Each model is traced as its `surface` (or LoadOptions::surface): its pool must hold those
    /// sections (splats: prt-octree; iso: prt-iso; mls: prt-mls; patches: prt-patches).
    static RenderScene load(const scene::Scene& scene, const std::filesystem::path& pool_override = {},
                            const LoadOptions& options = {});
    /// A pool on its own: the default scene (default material, one light, default_camera() at
    /// 512 x 512 with +y up); the surface is what the pool holds unless `options` names one.
    static RenderScene from_pool(const std::filesystem::path& pool, LoadOptions options = {});
    /// A scene whose models are given as already-open pools (tests, benchmarks).
    static RenderScene from_pools(const scene::Scene& scene,
                                  std::vector<std::shared_ptr<const pool::PoolFile>> pools,
                                  const LoadOptions& options = {});

    /// The host view for the CPU backend (and the source the CUDA backend uploads).
    core::SceneView view() const;

    /// The scene as parsed (camera, lights, materials in the world frame).
    const scene::Scene& scene() const { return m_scene; }
    scene::Scene& scene() { return m_scene; }
    /// Converts a world-frame camera into the render frame (double, then float).
    core::PinholeCamera camera(const scene::Camera& world_camera) const;
    core::PinholeCamera camera() const { return camera(m_scene.camera); }
    /// Render settings from the scene file.
    core::RenderParams params() const { return m_params; }
    core::RenderParams& params() { return m_params; }
    /// World position of the render frame's origin.
    const DVec3& render_origin() const { return m_origin; }
    /// World bounds of all models.
    DVec3 world_min() const { return m_world_min; }
    DVec3 world_max() const { return m_world_max; }
    const std::vector<LoadedModel>& models() const { return m_models; }
    /// Bytes of all sections the renderer reads (what a GPU upload moves; deferred bricks: their
    /// index only).
    std::uint64_t bytes() const;
    /// Whether a model's bricks were deferred (LoadOptions::defer_bricks) and are not loaded yet.
    bool has_deferred_bricks() const;
    /// Loads every deferred brick as a load without defer_bricks does (each brick checked by its
    /// checksum, leaf bounds over all bricks): the in-core path. Throws prt::Error naming the pool
    /// and the brick when one is corrupted.
    void load_deferred_bricks();
    /// Replaces model m's brick view (streaming: resident table, use and request flags, leaf bounds
    /// per slot) in the views view() returns; the arrays must outlive their use.
    void set_brick_view(std::size_t m, const core::BrickView& bricks);
    /// Lights after area-light expansion (SCENE.md: samples x samples point lights each).
    const std::vector<core::PointLight>& lights() const { return m_lights; }
    /// Rebuilds the render-frame lights from scene().point_lights/area_lights (after editing them).
    void update_lights();
    /// Warnings collected while loading (clamped settings, unsupported surfaces, ...), one line each.
    const std::vector<std::string>& warnings() const { return m_warnings; }
    /// Notes collected while loading (how intensities are shaded), one line each.
    const std::vector<std::string>& notes() const { return m_notes; }

    /// Robust world bounds of the models' points (scan_frame.h: 1st-99th percentile box grown to
    /// the points near it, over a sample of at most 200k points), the box a default view frames.
    /// Computed once; the models' bounds when they hold no points.
    const Box& robust_bounds() const;
    /// The up direction of the first model's points (scan_frame.h detect_up), in the world frame
    /// (turned by the model's transform); +y without models.
    UpDetection detect_up(const UpParams& params = {}) const;
    /// The side the data was seen from, a world direction: from the centre of robust_bounds()
    /// toward the first sensor of the first model whose pool has a sensors section; else, when the
    /// mean of the normals (a sample over all models) is at least 0.25 long, its direction (a
    /// single-view scan: its splats face the scanner; closed models' normals average near 0);
    /// else none.
    std::optional<DVec3> front_hint() const;
    /// The default view of the models: a camera framing the sample of points inside
    /// robust_bounds() (frame_points) with this up and vertical field of view, looking from
    /// default_direction(up, front_hint()).
    scene::Camera default_camera(std::uint32_t width, std::uint32_t height, const DVec3& up = {0, 1, 0},
                                 double fov_y_degrees = 45.0) const;
    /// Replaces the scene's lights by the default one, and updates the render-frame lights. From
    /// outside robust_bounds() the camera gets a light right of, above and behind it (from its
    /// look-at point: 1.5, 3 and 2.5 x the radius of robust_bounds(), along the camera's right,
    /// its up and the way back to it); from inside (a room scan), a light inside the box, above and
    /// right of the camera (half the way to the box along up, a third along right), which walls
    /// that enclose the camera do not shut out.
    void place_default_light();

    /// The default viewing direction (from the model toward the camera) for an up direction: the
    /// front, a little above (front + 0.35 up). The front is `front_hint` made perpendicular to up
    /// (the side a scanner saw) when given and not along up, else +z turned perpendicular to up
    /// (+y up: +z, so the default view of a y-up model looks down -z), else -y for +z up and +y for -z up.
    static DVec3 default_direction(const DVec3& up, const std::optional<DVec3>& front_hint = std::nullopt);
    /// A camera framing the box [lo, hi]: frame_points() of its 8 corners.
    static scene::Camera framing_camera(const DVec3& lo, const DVec3& hi, std::uint32_t width,
                                        std::uint32_t height, DVec3 direction = {0.0, 0.35, 1.0},
                                        DVec3 up = {0.0, 1.0, 0.0}, double fov_y_degrees = 45.0);
    /// A camera looking along `-direction` with this up and vertical fov that frames `points`: the
    /// look-at point is their bounds' centre moved across the view to centre their extent (as seen
    /// along the view), and the camera stands at the nearest distance at which every point lies
    /// inside the image with a 5 % border (both fields of view, from width / height).
    static scene::Camera frame_points(const std::vector<DVec3>& points, std::uint32_t width,
                                      std::uint32_t height, DVec3 direction = {0.0, 0.35, 1.0},
                                      DVec3 up = {0.0, 1.0, 0.0}, double fov_y_degrees = 45.0);

private:
    void apply_load_options(const LoadOptions& options);
    void build(std::vector<std::shared_ptr<const pool::PoolFile>> pools);
    void convert_materials();
    void load_environment();

    scene::Scene m_scene;
    bool m_surface_auto = false;                           ///< LoadOptions::surface "auto"
    std::optional<scene::SurfaceKind> m_surface_override;  ///< LoadOptions::surface naming a kind
    bool m_iso_float = false;
    bool m_bricks = false;
    bool m_defer_bricks = false;
    bool m_node_boxes = false, m_macro_regions = true;  ///< LoadOptions::empty_space (apply_load_options)
    core::RenderParams m_params;
    DVec3 m_origin{0, 0, 0};
    DVec3 m_world_min{0, 0, 0}, m_world_max{0, 0, 0};
    std::vector<LoadedModel> m_models;
    std::vector<core::ModelView> m_model_views;
    std::vector<core::Material> m_materials;
    std::vector<core::PointLight> m_lights;  ///< point lights, then area-light samples
    std::uint32_t m_point_light_count = 0;
    std::vector<core::AreaLight> m_area_lights;
    FloatImage m_environment;
    std::vector<std::string> m_warnings;
    std::vector<std::string> m_notes;
    std::optional<scene::PointColors> m_point_colors_override;  ///< LoadOptions::point_colors
    mutable std::optional<Box> m_robust;                        ///< robust_bounds(), once computed
    mutable std::vector<DVec3> m_robust_points;                 ///< the sample inside it (world)
};

/// Converts a scene file's render settings to core parameters (clamping max_bounces to
/// core::k_max_bounces; a warning is appended when it clamps).
core::RenderParams to_params(const scene::RenderSettings& s, std::vector<std::string>* warnings = nullptr);

/// Rotation of SCENE.md's transform: about X, then Y, then Z, in degrees: R = Rz Ry Rx.
std::array<DVec3, 3> rotation_matrix(const DVec3& degrees);

}  // namespace prt::rt
