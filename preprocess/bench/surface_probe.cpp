#include "surface_probe.h"

#include <initializer_list>

#include "prt/formats/scene.h"
#include "prt/runtime/render_scene.h"
#include "prt/runtime/surface_pools.h"

namespace prt::bench {

namespace {

/// Payload bytes of the sections of `types` the pool holds.
std::uint64_t section_bytes(const pool::PoolFile& p, std::initializer_list<pool::SectionType> types) {
    std::uint64_t n = 0;
    for (pool::SectionType t : types)
        if (const pool::SectionEntry* e = p.find(t)) n += e->size;
    return n;
}

}  // namespace

SurfaceProbe::SurfaceProbe(std::shared_ptr<const pool::PoolFile> pool, const std::string& surface,
                           const SurfaceSettings& s)
    : m_pool(std::move(pool)), m_surface(surface), m_s(s) {
    const pool::PoolFile& p = *m_pool;
    if (!scene::parse_surface(surface, m_kind))
        throw Error("unknown surface \"" + surface + "\" (" + std::string(scene::k_surface_name_list) + ")");
    switch (m_kind) {
        case scene::SurfaceKind::splats: {
            // RenderScene derives the leaf bounds the renderer culls with (runtime/host).
            scene::Scene sc;
            m_scene = std::make_unique<rt::RenderScene>(rt::RenderScene::from_pools(sc, {m_pool}));
            const core::ModelView& mv = m_scene->models().at(0).view;
            if (mv.bricks.top_nodes != nullptr)  // issue 17: measuring bricks is later work
                throw Error(p.label() +
                            ": a bricked pool without its float octree: not measured yet (build it "
                            "with prt-bricks --keep-float to measure the float splats)");
            m_octree = &mv.octree;
            m_colors = mv.colors;
            m_bytes = m_scene->bytes();
            break;
        }
        case scene::SurfaceKind::iso:
            m_iso = rt::load_iso_view(p, s.iso_storage == "q8");
            if ((s.iso_storage == "q8") != (m_iso.use_q8 && m_iso.leaves_q8 != nullptr))
                throw Error(p.label() + ": the pool has no " + s.iso_storage +
                            " ISO leaves (prt-iso --storage)");
            m_bytes = section_bytes(p, {pool::SectionType::iso_info, pool::SectionType::iso_nodes,
                                        s.iso_storage == "q8" ? pool::SectionType::iso_leaves_q8
                                                              : pool::SectionType::iso_leaves_f32});
            m_iso_params.refine_steps = s.iso_refine;
            m_iso_params.samples = s.iso_samples;
            break;
        case scene::SurfaceKind::mls:
            m_mls = rt::load_mls_view(p);
            m_bytes = section_bytes(p, {pool::SectionType::mls_info, pool::SectionType::mls_nodes,
                                        pool::SectionType::mls_refs, pool::SectionType::mls_splats,
                                        pool::SectionType::mls_bvh_nodes, pool::SectionType::mls_bvh_leaves});
            m_mls_params.samples = s.mls_k;
            m_mls_params.refine_steps = s.mls_refine;
            m_mls_params.samples_per_support = s.mls_support_samples;
            m_mls_params.faces = s.mls_both_faces ? core::k_mls_faces_both : core::k_mls_faces_by_ray;
            break;
        case scene::SurfaceKind::patches:
            m_patches = rt::load_patch_view(p);
            m_bytes =
                section_bytes(p, {pool::SectionType::patch_info, pool::SectionType::patch_control_points,
                                  pool::SectionType::patch_bvh, pool::SectionType::patch_subpatch_boxes});
            m_patch_params.max_iterations = s.patch_iterations;
            m_patch_params.tolerance = s.patch_tolerance;
            break;
    }
}

SurfaceProbe::~SurfaceProbe() = default;

template <class Hit>
bool SurfaceProbe::record(bool hit, const Hit& h, std::uint64_t work, std::uint64_t truncated,
                          ProbeHit& out) const {
    if (hit) out.t = h.t, out.normal = h.normal;
    m_work += work;
    m_truncated += truncated;
    return hit;
}

bool SurfaceProbe::trace(const core::Ray& r, ProbeHit& out) const {
    ++m_rays;
    bool hit = false;
    if (m_kind == scene::SurfaceKind::splats) {
        core::SplatSample s{};
        core::WalkStats ws;
        const core::BlendOptions blend{m_s.blend_window, m_s.deep};
        hit = core::closest_hit_splats(*m_octree, m_colors, r.origin, r.dir, false, core::k_inf, blend,
                                       1u << 16, s, ws, m_s.leaf_culling);
        return record(hit, s, ws.splat_tests, ws.truncated, out);
    } else if (m_kind == scene::SurfaceKind::iso) {
        core::IsoHit h;
        core::IsoStats st;
        hit = core::trace_iso(m_iso, r.origin, r.dir, core::k_inf, false, m_iso_params, h, st);
        return record(hit, h, st.evaluations, st.truncated, out);
    } else if (m_kind == scene::SurfaceKind::mls) {
        core::MlsHit h;
        core::MlsStats st;
        hit = m_s.mls_precision == "double"
                  ? core::trace_mls<double>(m_mls, r.origin, r.dir, core::k_inf, false, m_mls_params, h, st)
                  : core::trace_mls<float>(m_mls, r.origin, r.dir, core::k_inf, false, m_mls_params, h, st);
        return record(hit, h, st.evaluations, st.truncated, out);
    } else {
        core::PatchHit h;
        core::PatchStats st;
        const core::PatchRay ray = core::make_patch_ray(r.origin, r.dir, core::k_inf, false);
        hit = m_s.patch_precision == "float"
                  ? core::trace_patches<core::PatchPrecision::f32>(m_patches, ray, m_patch_params, h, &st)
                  : core::trace_patches(m_patches, ray, m_patch_params, h, &st);
        if (hit) {
            out.t = h.t;
            out.normal = core::to_vec3(h.normal);
            out.has_position = true;
            out.position = {h.position.x, h.position.y, h.position.z};
        }
        m_work += st.newton_iterations;
    }
    return hit;
}

nlohmann::json SurfaceProbe::settings() const {
    if (m_kind == scene::SurfaceKind::splats)
        return {{"deep_blending", m_s.deep},
                {"leaf_culling", m_s.leaf_culling},
                {"blend_window", m_s.blend_window}};
    if (m_kind == scene::SurfaceKind::iso)
        return {{"storage", m_s.iso_storage}, {"refine", m_s.iso_refine}, {"samples", m_s.iso_samples}};
    if (m_kind == scene::SurfaceKind::mls)
        return {{"k", m_s.mls_k},
                {"refine", m_s.mls_refine},
                {"support_samples", m_s.mls_support_samples},
                {"precision", m_s.mls_precision},
                {"faces", m_s.mls_both_faces ? "both" : "by_ray"}};
    return {{"subpatch_depth", m_patches.subpatch_depth},
            {"max_iterations", m_s.patch_iterations},
            {"tolerance", m_s.patch_tolerance},
            {"precision", m_s.patch_precision}};
}

nlohmann::json SurfaceProbe::work() const {
    const double rays = double(std::max<std::uint64_t>(1, m_rays.load()));
    const char* key = m_kind == scene::SurfaceKind::splats    ? "splat_tests_per_ray"
                      : m_kind == scene::SurfaceKind::patches ? "newton_iterations_per_ray"
                                                              : "evaluations_per_ray";
    return {{key, double(m_work.load()) / rays}, {"truncated_walks", m_truncated.load()}};
}

void add_surface_options(CLI::App& app, SurfaceSettings& s) {
    app.add_flag(
        "--deep-blending,!--no-deep-blending", s.deep,
        "splats: blend across leaf borders, thesis 3.5 (the renderer's default); --no-deep-blending: "
        "within one leaf");
    app.add_option("--leaf-culling", s.leaf_culling, "splats: 0 none, 1 cones, 2 cones + slabs")
        ->check(CLI::Range(0u, 2u));
    app.add_option("--blend-window", s.blend_window, "splats: blending window in radii")
        ->check(CLI::Range(0.0f, 100.0f));
    app.add_option("--iso-storage", s.iso_storage, "iso: q8 or f32 leaves")
        ->check(CLI::IsMember({"q8", "f32"}));
    app.add_option("--iso-refine", s.iso_refine, "iso: Illinois refinement steps, 0 = off")
        ->check(CLI::Range(0u, 32u));
    app.add_option("--iso-samples", s.iso_samples, "iso: sample intervals per leaf edge")
        ->check(CLI::Range(1.0f, 64.0f));
    app.add_option("--mls-k", s.mls_k, "mls: samples per cell interval, WS05 3.2.2's k")
        ->check(CLI::Range(2u, 256u));
    app.add_option("--mls-refine", s.mls_refine, "mls: Illinois refinement steps")
        ->check(CLI::Range(0u, 32u));
    app.add_option("--mls-support-samples", s.mls_support_samples,
                   "mls: at least this many samples per support radius of ray length in a cell (0: k alone)")
        ->check(CLI::Range(0.0f, 64.0f));
    app.add_option("--mls-precision", s.mls_precision, "mls: float or double accumulation")
        ->check(CLI::IsMember({"float", "double"}));
    app.add_option("--patch-iterations", s.patch_iterations, "patches: Newton iteration cap")
        ->check(CLI::Range(1u, 256u));
    app.add_option("--patch-tolerance", s.patch_tolerance,
                   "patches: Newton residual tolerance, relative to the model extent")
        ->check(CLI::Range(1e-16, 1e-1));
    app.add_option("--patch-precision", s.patch_precision,
                   "patches: Newton in double (the renderer's, seed 002) or float; the hit is "
                   "evaluated in double at the root either way")
        ->check(CLI::IsMember({"double", "float"}));
}

}  // namespace prt::bench
