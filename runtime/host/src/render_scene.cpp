#include "prt/runtime/render_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

#include "prt/error.h"
#include "prt/formats/brick_sections.h"
#include "prt/formats/octree_sections.h"
#include "prt/runtime/gi_pool.h"
#include "prt/runtime/leaf_bounds.h"
#include "prt/runtime/surface_pools.h"

namespace prt::rt {

namespace {

DVec3 mat_apply(const std::array<DVec3, 3>& m, const DVec3& v) {
    DVec3 r{};
    for (int i = 0; i < 3; ++i) r[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    return r;
}
core::Vec3 to_f(const DVec3& v) {
    return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}
core::Vec3 to_f(const scene::Color& c) {
    return {c[0], c[1], c[2]};
}

/// World position of a model-local point: translate + R (scale (origin + local)).
struct Placement {
    std::array<DVec3, 3> rotation;
    double scale;
    DVec3 translate;
    DVec3 origin;
    DVec3 world(const DVec3& local) const {
        return add(translate, mat_apply(rotation, mul(add(origin, local), scale)));
    }
};

Placement placement(const scene::Transform& t, const pool::ModelInfo& info) {
    Placement p;
    p.rotation = rotation_matrix(t.rotate_degrees);
    p.scale = t.scale;
    p.translate = t.translate;
    p.origin = {info.origin[0], info.origin[1], info.origin[2]};
    return p;
}

bool has_float_splats(const pool::PoolFile& pf) {
    return pf.has(pool::SectionType::octree_info) || pf.has(pool::SectionType::octree_nodes) ||
           pf.has(pool::SectionType::splats);
}
/// Splats: the float octree (16-19) or bricks (128-132, prt-bricks), or both.
bool has_splats(const pool::PoolFile& pf) {
    return has_float_splats(pf) || pool::has_bricks(pf);
}

/// The surface a model is traced as: the one asked for, or without one ("auto") the first the pool
/// holds of splats, patches, ISO, MLS. Splats asked of a pool without splat sections but with another
/// surface (a scene's default on a patch pool named without "surface") take that one with a warning.
core::SurfaceKind choose_surface(const pool::PoolFile& pf, std::optional<core::SurfaceKind> asked,
                                 const std::string& model, std::vector<std::string>& warnings) {
    if (asked && (*asked != core::SurfaceKind::splats || has_splats(pf))) return *asked;
    core::SurfaceKind k = core::SurfaceKind::splats;
    if (has_splats(pf)) {
        k = core::SurfaceKind::splats;
    } else if (has_patches(pf)) {
        k = core::SurfaceKind::patches;
    } else if (has_iso(pf)) {
        k = core::SurfaceKind::iso;
    } else if (has_mls(pf)) {
        k = core::SurfaceKind::mls;
    } else {
        pf.fail(nullptr,
                "no surface to render: no octree (prt-octree), ISO (prt-iso), MLS (prt-mls) or patch "
                "(prt-patches) sections");
    }
    if (asked)
        warnings.push_back("model '" + model + "': the pool has no splat octree: rendering its " +
                           std::string(scene::surface_name(k)) + " surface (set models[].surface)");
    return k;
}

/// The macro-regions of a tree's empty leaves (rt::build_macro_regions) into the model, and `tree`
/// pointed at them and at the node words that index them (the same bytes as the pool's words, which
/// they replace on the device). None when the tree's layout does not allow them.
void load_macro_regions(core::OctreeView& tree, LoadedModel& lm) {
    MacroRegions mr = build_macro_regions(tree);
    if (mr.regions.empty()) return;
    lm.region_nodes = std::move(mr.nodes);
    lm.macro_regions = std::move(mr.regions);
    tree.nodes = lm.region_nodes.data();  // a vector's buffer survives the moves of LoadedModel
    tree.macro_regions = lm.macro_regions.data();
    tree.macro_region_count = static_cast<std::uint32_t>(lm.macro_regions.size());
    lm.bytes += lm.macro_regions.size() * sizeof(core::MacroRegion);
}

/// The splat sections (thesis 3.2) of a pool into the model's octree view, with its leaf bounds,
/// node boxes and macro-regions.
/// PoolFile::open checked the octree (formats/POOL.md, "Validation"); what is left is the renderer's
/// own limit of 32-bit counts.
void load_splats(const pool::PoolFile& pf, LoadedModel& lm, bool node_boxes, bool macro_regions) {
    const pool::SplatOctreeSections s = pool::splat_octree(pf, "prt-play (build the octree with prt-octree)");
    if (s.nodes.size() > 0xffffffffull || s.splats.size() > 0xffffffffull)
        pf.fail(nullptr, "more than 2^32 - 1 nodes or splats: not supported by the renderer");
    core::OctreeView& o = lm.view.octree;
    o = core::make_octree_view(s.info, s.nodes.data(), s.leaf_info.data(), s.splats.data());
    lm.leaf_bounds = build_leaf_bounds(o);
    o.leaf_bounds = lm.leaf_bounds.data();  // a vector's buffer survives the moves of LoadedModel
    NodeBoxes nb = node_boxes ? build_node_boxes(o) : NodeBoxes{};
    lm.node_boxes = std::move(nb.boxes);
    lm.node_box_mask = std::move(nb.mask);
    o.node_boxes = lm.node_boxes.empty() ? nullptr : lm.node_boxes.data();
    o.node_box_mask = lm.node_boxes.empty() ? nullptr : lm.node_box_mask.data();
    lm.bytes = s.nodes.size_bytes() + s.leaf_info.size_bytes() + s.splats.size_bytes() +
               lm.leaf_bounds.size() * sizeof(core::LeafBounds) +
               lm.node_boxes.size() * sizeof(core::NodeBox);
    if (macro_regions) load_macro_regions(o, lm);
}

/// The brick sections (issue 17, prt-bricks) of a pool into the model's brick view, every brick
/// resident (in core; streaming changes only the view's resident table, rt::BrickStream). The
/// sections and every brick's payload are validated (pool::validate_bricks). With `defer`, only the
/// index is (pool::validate_brick_index): payloads stay unread and the view has no leaf bounds.
/// Bricks carry their splats' colours and no source point: per-point colors, intensities and
/// material ids do not apply (said once).
void load_bricks(const pool::PoolFile& pf, LoadedModel& lm, std::vector<std::string>& warnings, bool defer) {
    const pool::BrickSections s = defer ? pool::validate_brick_index(pf) : pool::validate_bricks(pf);
    lm.view.bricks = core::make_brick_view(
        s.info, s.top_nodes.data(), s.table.data(), reinterpret_cast<const unsigned char*>(s.data.data()),
        s.data.size(), s.lod.data(), s.lod_table.empty() ? nullptr : s.lod_table.data(),
        s.lod_table.empty() ? nullptr : s.lod_nodes.data(),
        s.lod_table.empty() ? nullptr : s.lod_discs.data(), static_cast<std::uint32_t>(s.lod_nodes.size()));
    lm.bricks_deferred = defer;
    // the resident index: top tree, table, top discs and the bricks' LOD prefixes
    lm.bytes = s.top_nodes.size_bytes() + s.table.size_bytes() + s.lod.size_bytes() +
               s.lod_table.size_bytes() + s.lod_nodes.size_bytes() + s.lod_discs.size_bytes();
    if (!defer) {
        // Leaf bounds over the decoded splats, so rays pass leaves unread as on the float path.
        lm.brick_leaf_bounds = build_brick_leaf_bounds(lm.view.bricks, lm.brick_leaf_first);
        lm.view.bricks.leaf_bounds =
            lm.brick_leaf_bounds.data();  // vectors' buffers survive LoadedModel's moves
        lm.view.bricks.leaf_bounds_first = lm.brick_leaf_first.data();
        lm.bytes += s.data.size_bytes() + lm.brick_leaf_bounds.size() * sizeof(core::BrickLeafBounds) +
                    lm.brick_leaf_first.size() * 4;
    }
    if (pf.has(pool::SectionType::material_ids) || pf.has(pool::SectionType::intensities))
        warnings.push_back("model '" + lm.name +
                           "': tracing bricks, which carry only RGB565 colours: the pool's material ids and "
                           "intensities are not used (the model's material shades every splat)");
}

/// SCENE.md point_colors: the per-point colors a model shades with (ModelView::colors). The pool's
/// colors are used in place; intensities become grey levels in a host array built here (so neither
/// the core nor a backend changes); points whose material asks for what the pool lacks get white.
/// ISO leaves carry colors baked by prt-iso and patches none: their view gets no per-point colors.
void shade_points(const pool::PoolFile& pf, LoadedModel& lm, const std::vector<scene::Material>& materials,
                  std::vector<std::string>& warnings, std::vector<std::string>& notes) {
    core::ModelView& v = lm.view;
    v.colors = nullptr;
    const std::size_t n = v.point_count;
    auto colors = pf.array<pool::Rgba8>(pool::SectionType::colors);
    auto intensities = pf.array<float>(pool::SectionType::intensities);
    if (!colors.empty() && colors.size() != n) {
        warnings.push_back(pf.label() + ": section colors: count differs from the point count: ignored");
        colors = {};
    }
    if (!intensities.empty() && intensities.size() != n) {
        warnings.push_back(pf.label() + ": section intensities: count differs from the point count: ignored");
        intensities = {};
    }
    // The materials this model's points use.
    const std::size_t nm = materials.size();
    std::vector<char> used(nm, 0);
    used[v.material] = 1;
    if (v.material_ids)
        for (std::size_t i = 0; i < n; ++i) used[std::min<std::size_t>(v.material_ids[i], nm - 1)] = 1;
    const bool per_point = v.surface == core::SurfaceKind::splats || v.surface == core::SurfaceKind::mls;
    if (!per_point) {
        for (std::size_t k = 0; k < nm; ++k) {
            if (used[k] && materials[k].point_colors == scene::PointColors::intensity &&
                v.surface == core::SurfaceKind::iso)
                warnings.push_back("model '" + lm.name +
                                   "': ISO leaves carry the colors prt-iso baked: build the ISO with prt-iso "
                                   "--point-colors intensity to shade it by intensity");
        }
        return;
    }
    // What each used material's points take: nothing (point_colors none: the core ignores them),
    // the pool's colors, grey levels, or white.
    enum class Take { skip, pool_colors, grey, white };
    std::vector<Take> take(nm, Take::skip);
    bool any_colors = false, any_grey = false, any_white = false;
    for (std::size_t k = 0; k < nm; ++k) {
        if (!used[k]) continue;
        Take t = Take::skip;
        switch (materials[k].point_colors) {
            case scene::PointColors::none:
                t = Take::skip;
                break;
            case scene::PointColors::automatic:
                t = !colors.empty() ? Take::pool_colors : !intensities.empty() ? Take::grey : Take::white;
                break;
            case scene::PointColors::colors:
                t = !colors.empty() ? Take::pool_colors : Take::white;
                break;
            case scene::PointColors::intensity:
                t = !intensities.empty() ? Take::grey : Take::white;
                if (intensities.empty())
                    warnings.push_back(
                        "model '" + lm.name + "': material " +
                        (materials[k].name.empty() ? std::to_string(k) : "'" + materials[k].name + "'") +
                        " shades by intensity but " + pf.label() + " has no intensities section");
                break;
        }
        take[k] = t;
        any_colors = any_colors || t == Take::pool_colors;
        any_grey = any_grey || t == Take::grey;
        any_white = any_white || t == Take::white;
    }
    if (!any_grey && !any_colors) return;         // white everywhere: no colors at all
    if (any_colors && !any_grey && !any_white) {  // the pool's own colors, in place
        v.colors = colors.data();
        return;
    }
    // Grey levels: each material's intensity_range, by default the pool's 1st-99th percentiles.
    std::optional<std::array<float, 2>> default_range;
    std::vector<std::array<float, 2>> range(nm, std::array<float, 2>{0, 0});
    for (std::size_t k = 0; k < nm; ++k) {
        if (take[k] != Take::grey) continue;
        if (materials[k].intensity_range) {
            range[k] = *materials[k].intensity_range;
        } else {
            if (!default_range) default_range = scene::intensity_range(intensities);
            range[k] = *default_range;
        }
        char buf[160];
        std::snprintf(buf, sizeof buf, "model '%s': shading by intensity, [%g, %g] to black..white%s",
                      lm.name.c_str(), double(range[k][0]), double(range[k][1]),
                      materials[k].intensity_range ? "" : " (the 1st-99th percentile)");
        if (std::find(notes.begin(), notes.end(), buf) == notes.end()) notes.push_back(buf);
        if (!(range[k][1] > range[k][0]))
            warnings.push_back("model '" + lm.name + "': the intensities have no spread: shaded white");
    }
    std::uint64_t non_finite = 0;
    lm.shading_colors.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = v.material_ids ? std::min<std::size_t>(v.material_ids[i], nm - 1) : v.material;
        pool::Rgba8& out = lm.shading_colors[i];
        switch (take[k]) {
            case Take::pool_colors:
                out = colors[i];
                break;
            case Take::grey: {
                const float x = intensities[i];
                non_finite += !std::isfinite(x);
                const std::uint8_t g = scene::intensity_grey(x, range[k][0], range[k][1]);
                out = pool::Rgba8{g, g, g, 255};
                break;
            }
            case Take::skip:
            case Take::white:
                out = pool::Rgba8{255, 255, 255, 255};
                break;
        }
    }
    if (non_finite)
        warnings.push_back("model '" + lm.name + "': " + std::to_string(non_finite) +
                           " intensities are not finite: shaded black");
    v.colors = lm.shading_colors.data();  // a vector's buffer survives the moves of LoadedModel
}

}  // namespace

std::array<DVec3, 3> rotation_matrix(const DVec3& degrees) {
    constexpr double k = 3.14159265358979323846 / 180.0;
    const double cx = std::cos(degrees[0] * k), sx = std::sin(degrees[0] * k);
    const double cy = std::cos(degrees[1] * k), sy = std::sin(degrees[1] * k);
    const double cz = std::cos(degrees[2] * k), sz = std::sin(degrees[2] * k);
    const std::array<DVec3, 3> rx{{{1, 0, 0}, {0, cx, -sx}, {0, sx, cx}}};
    const std::array<DVec3, 3> ry{{{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}}};
    const std::array<DVec3, 3> rz{{{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}}};
    auto matmul = [](const std::array<DVec3, 3>& a, const std::array<DVec3, 3>& b) {
        std::array<DVec3, 3> r{};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        return r;
    };
    return matmul(rz, matmul(ry, rx));  // X first, then Y, then Z
}

core::RenderParams to_params(const scene::RenderSettings& s, std::vector<std::string>* warnings) {
    core::RenderParams p;
    p.max_bounces = s.max_bounces;
    if (p.max_bounces > core::k_max_bounces) {
        if (warnings) {
            warnings->push_back("render.max_bounces " + std::to_string(s.max_bounces) +
                                " is above the runtime's limit of " + std::to_string(core::k_max_bounces) +
                                ": using " + std::to_string(core::k_max_bounces));
        }
        p.max_bounces = core::k_max_bounces;
    }
    p.shadows = s.shadows;
    p.reflections = s.reflections;
    p.refractions = s.refractions;
    p.exposure = s.exposure;
    p.gamma = s.gamma;
    p.path_tracing = s.path_tracing ? 1u : 0u;
    p.spp = std::max<std::uint32_t>(s.spp, 1);
    return p;
}

void RenderScene::apply_load_options(const LoadOptions& options) {
    m_surface_auto = options.surface == "auto";
    m_surface_override.reset();
    scene::SurfaceKind k{};
    if (!options.surface.empty() && !m_surface_auto) {
        if (!scene::parse_surface(options.surface, k))
            throw Error("unknown surface \"" + options.surface + "\" (expected auto, " +
                        std::string(scene::k_surface_name_list) + ")");
        m_surface_override = k;
    }
    m_iso_float = options.iso_float;
    m_bricks = options.bricks;
    m_defer_bricks = options.defer_bricks;
    // The default: runtime/README.md, "Macro-regions" (measured in
    // preprocess/bench/results/h100-2026-12-05-issue19-macro-regions).
    const std::string e =
        options.empty_space.empty() ? std::string(k_default_empty_space) : options.empty_space;
    if (e != "regions" && e != "boxes" && e != "both" && e != "none")
        throw Error("unknown empty-space walk \"" + e + "\" (expected regions, boxes, both or none)");
    m_node_boxes = e == "boxes" || e == "both";
    m_macro_regions = e == "regions" || e == "both";
    m_point_colors_override = options.point_colors;
}

RenderScene RenderScene::load(const scene::Scene& sc, const std::filesystem::path& pool_override,
                              const LoadOptions& options) {
    RenderScene r;
    r.m_scene = sc;
    r.apply_load_options(options);
    std::vector<std::shared_ptr<const pool::PoolFile>> pools;
    if (!pool_override.empty()) {
        scene::Model m;
        if (!sc.models.empty()) m = sc.models.front();
        m.name = pool_override.stem().string();
        m.pool = pool_override;
        m.source.clear();
        r.m_scene.models = {m};
    }
    for (scene::Model& m : r.m_scene.models) {
        // SCENE.md: a model given only by its source has its pool where prt-bake writes it.
        if (m.pool.empty() && !m.source.empty() && !sc.file.empty())
            m.pool = sc.file.parent_path() / "pools" / (m.source.stem().string() + ".pool");
        if (m.pool.empty() || (!m.source.empty() && !std::filesystem::exists(m.pool))) {
            throw Error((sc.file.empty() ? std::string("scene") : sc.file.string()) + ": model '" + m.name +
                        "' has no pool (run prt-bake to build it from " + m.source.string() + ")");
        }
        // Brick payloads are checked brick by brick when loaded (load_bricks: validate_bricks), so
        // the open does not checksum the whole brick_data section first; every other check runs.
        pool::OpenOptions open;
        open.defer_brick_payloads = true;
        pools.push_back(std::make_shared<const pool::PoolFile>(pool::PoolFile::open(m.pool, open)));
    }
    r.build(std::move(pools));
    return r;
}

RenderScene RenderScene::from_pools(const scene::Scene& sc,
                                    std::vector<std::shared_ptr<const pool::PoolFile>> pools,
                                    const LoadOptions& options) {
    RenderScene r;
    r.m_scene = sc;
    r.apply_load_options(options);
    while (r.m_scene.models.size() < pools.size()) r.m_scene.models.push_back(scene::Model{});
    r.m_scene.models.resize(pools.size());
    r.build(std::move(pools));
    return r;
}

RenderScene RenderScene::from_pool(const std::filesystem::path& path, LoadOptions options) {
    if (options.surface.empty()) options.surface = "auto";
    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    sc.materials.back().name = "default";
    scene::Model m;
    m.name = path.stem().string();
    m.pool = path;
    sc.models.push_back(m);
    RenderScene r = load(sc, {}, options);
    // Default view: frame the model's robust bounds, one light above and to the right of the camera.
    r.m_scene.camera = r.default_camera(r.m_scene.camera.width, r.m_scene.camera.height);
    r.place_default_light();
    return r;
}

const Box& RenderScene::robust_bounds() const {
    if (m_robust) return *m_robust;
    // A strided sample of every model's points in the world frame, at most k_sample in all.
    constexpr std::size_t k_sample = 200000;
    std::size_t total = 0;
    for (const LoadedModel& lm : m_models)
        total += lm.pool->array<pool::Float3>(pool::SectionType::positions).size();
    std::vector<DVec3> sample;
    if (total > 0) {
        const std::size_t stride = (total + k_sample - 1) / k_sample;
        sample.reserve(total / stride + m_models.size());
        for (std::size_t i = 0; i < m_models.size(); ++i) {
            const pool::PoolFile& pf = *m_models[i].pool;
            const Placement pl = placement(m_scene.models[i].transform, pf.model_info());
            const auto pos = pf.array<pool::Float3>(pool::SectionType::positions);
            for (std::size_t k = 0; k < pos.size(); k += stride) {
                const DVec3 w = pl.world({pos[k].x, pos[k].y, pos[k].z});
                if (std::isfinite(w[0]) && std::isfinite(w[1]) && std::isfinite(w[2])) sample.push_back(w);
            }
        }
    }
    m_robust_points.clear();
    Box b = rt::robust_bounds(sample, 0.25, &m_robust_points);
    if (!b.valid) {
        b.lo = m_world_min;
        b.hi = m_world_max;
        b.valid = true;
        for (int corner = 0; corner < 8; ++corner)
            m_robust_points.push_back({(corner & 1) ? b.hi[0] : b.lo[0], (corner & 2) ? b.hi[1] : b.lo[1],
                                       (corner & 4) ? b.hi[2] : b.lo[2]});
    }
    m_robust = b;
    return *m_robust;
}

UpDetection RenderScene::detect_up(const UpParams& params) const {
    if (m_models.empty()) return rt::detect_up(UpInput{}, params);
    const pool::PoolFile& pf = *m_models.front().pool;
    const pool::ModelInfo& info = pf.model_info();
    UpInput in;
    in.positions = pf.array<pool::Float3>(pool::SectionType::positions);
    in.normals = pf.array<pool::Float3>(pool::SectionType::normals);
    in.sensors = pf.array<pool::Sensor>(pool::SectionType::sensors);
    in.origin = {info.origin[0], info.origin[1], info.origin[2]};
    UpDetection d = rt::detect_up(in, params);
    // Into the world frame: the model's rotation (its scale is positive and uniform).
    const Placement pl = placement(m_scene.models.front().transform, info);
    const DVec3 w = mat_apply(pl.rotation, d.up);
    const double len = length(w);
    if (len > 0) d.up = mul(w, 1.0 / len);
    return d;
}

std::optional<DVec3> RenderScene::front_hint() const {
    for (std::size_t i = 0; i < m_models.size(); ++i) {
        const pool::PoolFile& pf = *m_models[i].pool;
        const auto sensors = pf.array<pool::Sensor>(pool::SectionType::sensors);
        if (sensors.empty()) continue;
        const pool::Sensor& s = sensors.front();
        const Placement pl = placement(m_scene.models[i].transform, pf.model_info());
        const DVec3 sp{s.position[0], s.position[1], s.position[2]};
        DVec3 d;
        if (s.kind == pool::k_sensor_direction) {
            d = mat_apply(pl.rotation, sp);
        } else {
            const Box& b = robust_bounds();
            d = sub(pl.world(sub(sp, pl.origin)), mul(add(b.lo, b.hi), 0.5));
        }
        const double len = length(d);
        if (len > 0 && std::isfinite(len)) return mul(d, 1.0 / len);
    }
    // No sensor: the mean normal (world frame) over a strided sample of at most 200k normals.
    constexpr std::size_t k_sample = 200000;
    std::size_t total = 0;
    for (const LoadedModel& lm : m_models)
        total += lm.pool->array<pool::Float3>(pool::SectionType::normals).size();
    if (total == 0) return std::nullopt;
    const std::size_t stride = (total + k_sample - 1) / k_sample;
    DVec3 sum{0, 0, 0};
    std::size_t count = 0;
    for (std::size_t i = 0; i < m_models.size(); ++i) {
        const pool::PoolFile& pf = *m_models[i].pool;
        const auto normals = pf.array<pool::Float3>(pool::SectionType::normals);
        const Placement pl = placement(m_scene.models[i].transform, pf.model_info());
        for (std::size_t k = 0; k < normals.size(); k += stride) {
            const DVec3 nl{normals[k].x, normals[k].y, normals[k].z};
            const double len = length(nl);
            if (!(len > 0) || !std::isfinite(len)) continue;
            sum = add(sum, mat_apply(pl.rotation, mul(nl, 1.0 / len)));
            ++count;
        }
    }
    if (count == 0) return std::nullopt;
    const DVec3 mean = mul(sum, 1.0 / static_cast<double>(count));
    const double len = length(mean);
    if (len >= 0.25) return mul(mean, 1.0 / len);
    return std::nullopt;
}

scene::Camera RenderScene::default_camera(std::uint32_t width, std::uint32_t height, const DVec3& up,
                                          double fov_y_degrees) const {
    robust_bounds();
    return frame_points(m_robust_points, width, height, default_direction(up, front_hint()), up,
                        fov_y_degrees);
}

void RenderScene::place_default_light() {
    const scene::Camera& cam = m_scene.camera;
    const Box& b = robust_bounds();
    const double radius = std::max(0.5 * length(sub(b.hi, b.lo)), 1e-30);
    DVec3 u = cam.up;
    const double ul = length(u);
    u = ul > 0 ? mul(u, 1.0 / ul) : DVec3{0, 1, 0};
    DVec3 back = sub(cam.position, cam.look_at);
    DVec3 right{u[1] * back[2] - u[2] * back[1], u[2] * back[0] - u[0] * back[2],
                u[0] * back[1] - u[1] * back[0]};
    const double rl = length(right);
    scene::PointLight light;
    const bool inside = b.valid && [&] {
        for (int a = 0; a < 3; ++a)
            if (!(cam.position[a] > b.lo[a] && cam.position[a] < b.hi[a])) return false;
        return true;
    }();
    if (rl > 0 && std::isfinite(rl)) {
        right = mul(right, 1.0 / rl);
        if (inside) {
            // The camera inside the model (a room, a corridor, a scan seen from its scanner): a
            // light outside would be walled off and leave the view in shadow. It goes above and
            // right of the camera, half the way to the bounds along up and a third along right: a
            // convex combination of the camera and two points of the box, so inside the box too.
            auto reach = [&](const DVec3& dir) {  // distance from the camera to the box along dir
                double t = std::numeric_limits<double>::infinity();
                for (int a = 0; a < 3; ++a) {
                    if (dir[a] > 0) t = std::min(t, (b.hi[a] - cam.position[a]) / dir[a]);
                    if (dir[a] < 0) t = std::min(t, (b.lo[a] - cam.position[a]) / dir[a]);
                }
                return std::isfinite(t) ? t : 0.0;
            };
            light.position = add(cam.position, add(mul(u, 0.5 * reach(u)), mul(right, reach(right) / 3.0)));
        } else {
            back = {right[1] * u[2] - right[2] * u[1], right[2] * u[0] - right[0] * u[2],
                    right[0] * u[1] - right[1] * u[0]};  // right x up: toward the camera, perpendicular to up
            light.position =
                add(cam.look_at, mul(add(add(mul(right, 1.5), mul(u, 3.0)), mul(back, 2.5)), radius));
        }
    } else {
        light.position = add(cam.look_at, mul(DVec3{1.5, 3.0, 2.5}, radius));
    }
    m_scene.point_lights = {light};
    m_scene.area_lights.clear();
    update_lights();
}

DVec3 RenderScene::default_direction(const DVec3& up_in, const std::optional<DVec3>& front_hint) {
    const double ul = length(up_in);
    const DVec3 up = ul > 0 && std::isfinite(ul) ? mul(up_in, 1.0 / ul) : DVec3{0, 1, 0};
    auto perpendicular = [&](const DVec3& v) {  // v without its component along up
        return sub(v, mul(up, v[0] * up[0] + v[1] * up[1] + v[2] * up[2]));
    };
    DVec3 front{0, 0, 0};
    if (front_hint) front = perpendicular(*front_hint);
    if (length(front) < 0.1) {
        if (std::fabs(up[2]) < 0.9)
            front = perpendicular({0, 0, 1});
        else
            front = perpendicular({0, up[2] > 0 ? -1.0 : 1.0, 0});
    }
    front = mul(front, 1.0 / length(front));
    return add(front, mul(up, 0.35));
}

scene::Camera RenderScene::framing_camera(const DVec3& lo, const DVec3& hi, std::uint32_t width,
                                          std::uint32_t height, DVec3 direction, DVec3 up,
                                          double fov_y_degrees) {
    std::vector<DVec3> corners;
    for (int corner = 0; corner < 8; ++corner)
        corners.push_back(
            {(corner & 1) ? hi[0] : lo[0], (corner & 2) ? hi[1] : lo[1], (corner & 4) ? hi[2] : lo[2]});
    return frame_points(corners, width, height, direction, up, fov_y_degrees);
}

scene::Camera RenderScene::frame_points(const std::vector<DVec3>& points, std::uint32_t width,
                                        std::uint32_t height, DVec3 direction, DVec3 up,
                                        double fov_y_degrees) {
    scene::Camera cam;
    cam.width = width;
    cam.height = height;
    cam.fov_y_degrees = fov_y_degrees > 0 && fov_y_degrees < 180 ? fov_y_degrees : 45.0;
    constexpr double k_inf = std::numeric_limits<double>::infinity();
    DVec3 lo{k_inf, k_inf, k_inf}, hi{-k_inf, -k_inf, -k_inf};
    for (const DVec3& p : points)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    if (points.empty()) lo = hi = {0, 0, 0};
    DVec3 c = mul(add(lo, hi), 0.5);
    double radius = 0.5 * length(sub(hi, lo));
    if (!(radius > 0) || !std::isfinite(radius)) radius = 1.0;
    double len = length(direction);
    direction = len > 0 && std::isfinite(len) ? mul(direction, 1.0 / len) : DVec3{0, 0, 1};
    len = length(up);
    up = len > 0 && std::isfinite(len) ? mul(up, 1.0 / len) : DVec3{0, 1, 0};
    // The camera frame: w toward the camera, r its right, u its (projected) up.
    auto cross = [](const DVec3& a, const DVec3& b) {
        return DVec3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    auto dot = [](const DVec3& a, const DVec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    const DVec3& w = direction;
    DVec3 r = cross(up, w);
    if (length(r) < 1e-6) {  // up along the view: any up perpendicular to it
        up = std::fabs(w[1]) < 0.9 ? DVec3{0, 1, 0} : DVec3{0, 0, 1};
        r = cross(up, w);
    }
    r = mul(r, 1.0 / length(r));
    const DVec3 u = cross(w, r);
    const double half = 0.5 * cam.fov_y_degrees * 3.14159265358979323846 / 180.0;
    const double aspect = height > 0 ? static_cast<double>(width) / height : 1.0;
    // With a 5 % border: a point p is inside the view from the eye E when, along the camera's
    // forward f = -w, |(p - E).r| <= tx (p - E).f and |(p - E).u| <= ty (p - E).f. In E's
    // coordinates (e_r, e_u, e_f) these are linear: e_r - tx e_f >= max(p.r - tx p.f) = A_r and
    // e_r + tx e_f <= min(p.r + tx p.f) = B_r (the same with u, ty). The nearest eye (largest e_f)
    // takes e_r = (A_r + B_r) / 2, e_u = (A_u + B_u) / 2 and e_f = min((B_r - A_r) / 2 tx,
    // (B_u - A_u) / 2 ty): exact, and the points' image is centred along the tighter axis.
    const double ty = std::tan(half) / 1.05, tx = std::tan(half) * aspect / 1.05;
    const DVec3 f = mul(w, -1.0);
    double ar = -k_inf, br = k_inf, au = -k_inf, bu = k_inf, nearest = k_inf;
    for (const DVec3& p : points) {
        const double pr = dot(p, r), pu = dot(p, u), pf = dot(p, f);
        ar = std::max(ar, pr - tx * pf);
        br = std::min(br, pr + tx * pf);
        au = std::max(au, pu - ty * pf);
        bu = std::min(bu, pu + ty * pf);
        nearest = std::min(nearest, pf);
    }
    if (!points.empty() && std::isfinite(ar + br + au + bu)) {
        const double er = 0.5 * (ar + br), eu = 0.5 * (au + bu);
        const double ef = std::min({(br - ar) / (2 * tx), (bu - au) / (2 * ty), nearest - 0.05 * radius});
        const DVec3 eye = add(add(mul(r, er), mul(u, eu)), mul(f, ef));
        cam.position = eye;
        cam.look_at = add(eye, mul(f, std::max(dot(sub(c, eye), f), 1e-9 * radius)));
        cam.up = up;
        return cam;
    }
    const double dist = radius / std::sin(half) * 1.05;
    cam.position = add(c, mul(w, dist));
    cam.look_at = c;
    cam.up = up;
    return cam;
}

void RenderScene::build(std::vector<std::shared_ptr<const pool::PoolFile>> pools) {
    m_warnings.clear();
    m_notes.clear();
    m_robust.reset();
    m_robust_points.clear();
    if (m_scene.materials.empty()) {
        m_scene.materials.push_back(scene::Material{});
        m_scene.materials.back().name = "default";
    }
    if (m_point_colors_override)
        for (scene::Material& m : m_scene.materials) m.point_colors = *m_point_colors_override;
    m_params = to_params(m_scene.render, &m_warnings);
    m_models.clear();
    constexpr double k_inf = std::numeric_limits<double>::infinity();
    m_world_min = {k_inf, k_inf, k_inf};
    m_world_max = {-k_inf, -k_inf, -k_inf};
    bool origin_set = false;
    for (std::size_t i = 0; i < pools.size(); ++i) {
        const pool::PoolFile& pf = *pools[i];
        const scene::Model& sm = m_scene.models[i];
        const pool::ModelInfo& info = pf.model_info();
        const auto material_ids = pf.array<std::uint32_t>(pool::SectionType::material_ids);
        if (info.point_count > 0xffffffffull)
            pf.fail(nullptr, "more than 2^32 - 1 points: not supported by the renderer");
        LoadedModel lm;
        lm.name = sm.name.empty() ? pf.label() : sm.name;
        lm.pool = pools[i];
        core::ModelView& v = lm.view;
        const std::optional<core::SurfaceKind> asked =
            m_surface_auto ? std::nullopt : std::optional{m_surface_override.value_or(sm.surface)};
        v.surface = choose_surface(pf, asked, lm.name, m_warnings);
        switch (v.surface) {
            case core::SurfaceKind::splats:
                // The float octree when the pool has one (unless bricks are asked for), else bricks.
                if (pool::has_bricks(pf) && (m_bricks || !has_float_splats(pf)))
                    load_bricks(pf, lm, m_warnings, m_defer_bricks);
                else
                    load_splats(pf, lm, m_node_boxes, m_macro_regions);
                break;
            case core::SurfaceKind::iso: {
                v.iso = load_iso_view(pf, !m_iso_float);
                if (v.iso.use_q8)  // upload only the leaves traced
                    v.iso.leaves_f32 = nullptr;
                else
                    v.iso.leaves_q8 = nullptr;
                const std::size_t leaf = v.iso.use_q8 ? sizeof(pool::IsoLeafQ8) : sizeof(pool::IsoLeafF32);
                lm.bytes = std::size_t{v.iso.tree.node_count} * 4 + std::size_t{v.iso.leaf_count} * leaf;
                // The ISO walk is the splat walk over the ISO's tree: its empty leaves get
                // macro-regions the same way (node boxes need splats: none here).
                if (m_macro_regions) load_macro_regions(v.iso.tree, lm);
                break;
            }
            case core::SurfaceKind::mls:
                v.mls = load_mls_view(pf);
                lm.bytes = std::size_t{v.mls.node_count} * sizeof(pool::MlsNode) +
                           std::size_t{v.mls.ref_count} * 4 +
                           std::size_t{v.mls.splat_count} * sizeof(pool::MlsSplat);
                break;
            case core::SurfaceKind::patches:
                v.patches = load_patch_view(pf);
                lm.bytes = std::size_t{v.patches.patch_count} * sizeof(pool::PatchControlNet) +
                           std::size_t{v.patches.bvh_node_count} * sizeof(pool::PatchBvhNode) +
                           std::size_t{v.patches.patch_count} * v.patches.subpatch_nodes *
                               sizeof(pool::SubpatchNode);
                break;
        }
        v.point_count = static_cast<std::uint32_t>(info.point_count);
        const bool bricked = v.bricks.top_nodes != nullptr;
        if (!material_ids.empty() && !bricked) {
            if (material_ids.size() == info.point_count)
                v.material_ids = material_ids.data();
            else
                m_warnings.push_back(pf.label() +
                                     ": section material_ids: count differs from the point count: ignored");
        }
        v.material =
            std::min<std::uint32_t>(sm.material, static_cast<std::uint32_t>(m_scene.materials.size() - 1));
        if (!bricked) shade_points(pf, lm, m_scene.materials, m_warnings, m_notes);
        lm.bytes += (v.colors ? std::size_t{v.point_count} * sizeof(pool::Rgba8) : 0) +
                    (v.material_ids ? material_ids.size_bytes() : 0);
        // thesis 5.3-5.4: precomputed global illumination, when the scene asks for it.
        const auto load_gi = [&](bool wanted, const char* option, bool present, auto load, auto& view,
                                 const char* missing) {
            if (!wanted) return;
            if (!present) {
                m_warnings.push_back("model '" + lm.name + "': render." + option + " is on but " +
                                     pf.label() + " has no " + missing);
                return;
            }
            view = load(pf);
            lm.bytes += std::size_t{view.tree.node_count} * 4 +
                        std::size_t{view.tree.leaf_count} * sizeof(pool::GiLeaf);
        };
        // Issue 20: a pool placed several times holds one caustic map and one light map per
        // placement, keyed by its transform (pool::placement_key).
        const std::uint32_t placement_id = pool::placement_key(sm.transform);
        load_gi(
            m_scene.render.caustics, "caustics", has_caustics(pf),
            [&](const pool::PoolFile& p) { return load_caustic_view(p, placement_id); }, v.caustics,
            "caustic octree (run prt-photons on the scene)");
        if (m_scene.render.caustics && has_caustics(pf) && v.caustics.tree.nodes == nullptr)
            m_notes.push_back("model '" + lm.name + "': " + pf.label() +
                              " has no caustic map for this placement (none reached it, or the scene moved "
                              "it since prt-photons ran)");
        load_gi(
            m_scene.render.light_map, "light_map", has_light_map(pf),
            [&](const pool::PoolFile& p) { return load_light_map_view(p, placement_id); }, v.light_map,
            "light map (run prt-lightmap on the scene)");
        if (m_scene.render.light_map && has_light_map(pf) && v.light_map.tree.nodes == nullptr)
            m_notes.push_back(
                "model '" + lm.name + "': " + pf.label() +
                " has no light map for this placement (the scene moved it since prt-lightmap ran)");

        const Placement pl = placement(sm.transform, info);
        const DVec3 world_origin = pl.world({0, 0, 0});
        if (!origin_set) {
            m_origin = world_origin;
            origin_set = true;
        }
        v.offset = to_f(sub(world_origin, m_origin));
        v.rotation = core::Mat3{to_f(pl.rotation[0]), to_f(pl.rotation[1]), to_f(pl.rotation[2])};
        v.scale = static_cast<float>(pl.scale);
        v.inv_scale = static_cast<float>(1.0 / pl.scale);
        lm.world_min = {k_inf, k_inf, k_inf};
        lm.world_max = {-k_inf, -k_inf, -k_inf};
        for (int corner = 0; corner < 8; ++corner) {
            const DVec3 local{(corner & 1) ? info.bounds_max[0] : info.bounds_min[0],
                              (corner & 2) ? info.bounds_max[1] : info.bounds_min[1],
                              (corner & 4) ? info.bounds_max[2] : info.bounds_min[2]};
            const DVec3 w = pl.world(local);
            for (int a = 0; a < 3; ++a) {
                lm.world_min[a] = std::min(lm.world_min[a], w[a]);
                lm.world_max[a] = std::max(lm.world_max[a], w[a]);
            }
        }
        for (int a = 0; a < 3; ++a) {
            m_world_min[a] = std::min(m_world_min[a], lm.world_min[a]);
            m_world_max[a] = std::max(m_world_max[a], lm.world_max[a]);
        }
        m_models.push_back(std::move(lm));
    }
    if (m_models.empty()) m_world_min = m_world_max = {0, 0, 0};
    m_model_views.clear();
    for (const LoadedModel& lm : m_models) m_model_views.push_back(lm.view);
    convert_materials();
    update_lights();
    load_environment();
}

void RenderScene::convert_materials() {
    m_materials.clear();
    for (const scene::Material& sm : m_scene.materials) {
        core::Material m;
        m.ambient = to_f(sm.ambient);
        m.diffuse = to_f(sm.diffuse);
        m.specular = to_f(sm.specular);
        m.specular_exponent = sm.specular_exponent;
        m.refractive_index = sm.refractive_index;
        m.reflectivity = sm.reflectivity;
        m.transmissivity = sm.transmissivity;
        m.diffuse_reflectance = sm.diffuse_reflectance;
        m.use_point_colors = sm.point_colors != scene::PointColors::none ? 1u : 0u;
        m_materials.push_back(m);
    }
}

void RenderScene::update_lights() {
    m_lights.clear();
    m_area_lights.clear();
    for (const scene::PointLight& l : m_scene.point_lights) {
        core::PointLight p;
        p.position = to_f(sub(l.position, m_origin));
        p.color = to_f(l.color) * l.intensity;
        p.casts_shadows = l.casts_shadows ? 1u : 0u;
        m_lights.push_back(p);
    }
    m_point_light_count = static_cast<std::uint32_t>(m_lights.size());
    // SCENE.md: an area light is samples x samples point lights on a regular grid, each carrying
    // intensity / samples^2 (seed 002, 5.6).
    for (const scene::AreaLight& a : m_scene.area_lights) {
        const std::uint32_t n = std::max<std::uint32_t>(a.samples, 1);
        const float share = a.intensity / static_cast<float>(n * n);
        for (std::uint32_t i = 0; i < n; ++i) {
            for (std::uint32_t j = 0; j < n; ++j) {
                const double u = (i + 0.5) / n, v = (j + 0.5) / n;
                const DVec3 w = add(a.corner, add(mul(a.edge_u, u), mul(a.edge_v, v)));
                core::PointLight p;
                p.position = to_f(sub(w, m_origin));
                p.color = to_f(a.color) * share;
                p.casts_shadows = a.casts_shadows ? 1u : 0u;
                m_lights.push_back(p);
            }
        }
        core::AreaLight al;  // the path tracer samples the parallelogram itself (path.h)
        al.corner = to_f(sub(a.corner, m_origin));
        al.edge_u = to_f(a.edge_u);
        al.edge_v = to_f(a.edge_v);
        al.color = to_f(a.color) * a.intensity;
        al.casts_shadows = a.casts_shadows ? 1u : 0u;
        m_area_lights.push_back(al);
    }
}

void RenderScene::load_environment() {
    m_environment = FloatImage{};
    if (!m_scene.environment.image.empty()) m_environment = read_float_image(m_scene.environment.image);
}

core::SceneView RenderScene::view() const {
    core::SceneView s;
    s.models = m_model_views.data();
    s.model_count = static_cast<std::uint32_t>(m_model_views.size());
    s.materials = m_materials.data();
    s.material_count = static_cast<std::uint32_t>(m_materials.size());
    s.lights = m_lights.data();
    s.light_count = static_cast<std::uint32_t>(m_lights.size());
    s.point_light_count = m_point_light_count;
    s.area_lights = m_area_lights.data();
    s.area_light_count = static_cast<std::uint32_t>(m_area_lights.size());
    s.environment.color = to_f(m_scene.environment.color);
    s.environment.intensity = m_scene.environment.intensity;
    if (!m_environment.rgb.empty()) {
        s.environment.image = m_environment.rgb.data();
        s.environment.width = m_environment.width;
        s.environment.height = m_environment.height;
    }
    s.params = m_params;
    return s;
}

core::PinholeCamera RenderScene::camera(const scene::Camera& c) const {
    return core::make_pinhole(to_f(sub(c.position, m_origin)), to_f(sub(c.look_at, m_origin)), to_f(c.up),
                              static_cast<float>(c.fov_y_degrees), c.width, c.height);
}

std::uint64_t RenderScene::bytes() const {
    std::uint64_t b = 0;
    for (const LoadedModel& m : m_models) b += m.bytes;
    return b;
}

bool RenderScene::has_deferred_bricks() const {
    for (const LoadedModel& m : m_models)
        if (m.bricks_deferred) return true;
    return false;
}

void RenderScene::load_deferred_bricks() {
    for (std::size_t i = 0; i < m_models.size(); ++i) {
        LoadedModel& lm = m_models[i];
        if (!lm.bricks_deferred) continue;
        std::vector<std::string> warnings;              // said once already, at the deferred load
        const std::uint64_t index_and_rest = lm.bytes;  // the index, and GI sections if any
        load_bricks(*lm.pool, lm, warnings, false);
        lm.bytes = index_and_rest + lm.view.bricks.data_bytes +
                   lm.brick_leaf_bounds.size() * sizeof(core::BrickLeafBounds) +
                   lm.brick_leaf_first.size() * 4;
        m_model_views[i].bricks = lm.view.bricks;
    }
}

void RenderScene::set_brick_view(std::size_t m, const core::BrickView& bricks) {
    m_models.at(m).view.bricks = bricks;
    m_model_views.at(m).bricks = bricks;
}

}  // namespace prt::rt
