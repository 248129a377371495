// prt-bench-embree: the CPU peer benchmark. The same splats, the same view and the same three
// scenarios as prt-bench (bench_scene.h: the 1M-point synthetic room seen from
// inside; primary, one shadow light, 4-bounce mirrors), rendered on the CPU twice in one run:
//   ours:   the CPU backend (the core's octree walk, thesis 2.2, and splat blending, 3.3), over the
//           replicated octree (every disk stored in every leaf it overlaps, thesis 3.4);
//   Embree: every point of the pool (not the octree's replicas) as one Embree 3 oriented disc
//           (RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT: centre, radius, normal) in Embree's own BVH,
//           traced one ray at a time (rtcIntersect1 / rtcOccluded1). An intersection filter applies
//           the seamless front/back rule of thesis 3.6 (outside rays accept only front faces,
//           inside rays only back faces, no minimum distance), so secondary and shadow rays leave
//           their surface exactly as ours do. Shading, secondary rays and tone mapping are the
//           core's functions (render.h); only closest-hit and any-hit queries differ.
// Both render with the same number of threads over 16x16 tiles, frame about frame (ours, Embree,
// ours, ...), so a shared machine's changing speed moves both alike; each scenario's frame time is
// the median over --frames frames after --warmup, and ours / Embree the median over the frame pairs.
//
// What differs, by design: ours blends the hits within the blending window (eq. 3.1, more work per
// hit); Embree returns the nearest disc. The run reports how often the two agree on the primary
// hit distance, to show that both trace the same surface.
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bench_scene.h"
#include "player_options.h"
#include "prt/core/render.h"
#include "prt/parallel.h"
#include "prt/runtime/backend.h"
#include "prt/tool.h"

namespace {

using namespace prt;

constexpr std::uint32_t k_tile = 16;

struct Options {
    player::BenchSceneOptions scene;
    std::uint32_t frames = 5, warmup = 1;
    unsigned threads = 0;
    std::string scenarios = "primary,shadow,reflect4";
    std::string json;
    player::RenderOverrides render;
};

/// Per Embree geometry (one per model): what the filter and the shading need.
struct DiscModel {
    std::vector<float> normals;  ///< unit normals, render frame, 3 per point
    std::uint32_t model = 0;
};

/// thesis 3.6 as an Embree intersection filter: a candidate hit counts only on the face the ray
/// expects (front for outside rays, back for inside rays; the ray's `id` carries the flag).
void seamless_filter(const RTCFilterFunctionNArguments* args) {
    const auto* model = static_cast<const DiscModel*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        const float* n = model->normals.data() + 3 * static_cast<std::size_t>(prim);
        const float dn = RTCRayN_dir_x(args->ray, args->N, i) * n[0] +
                         RTCRayN_dir_y(args->ray, args->N, i) * n[1] +
                         RTCRayN_dir_z(args->ray, args->N, i) * n[2];
        const bool inside = (RTCRayN_id(args->ray, args->N, i) & core::k_ray_inside) != 0;
        if (!core::face_expected(dn, inside)) args->valid[i] = 0;
    }
}

/// The scene's splats as Embree oriented discs, in the render frame.
class EmbreeScene {
public:
    EmbreeScene(const rt::RenderScene& rs, unsigned threads) {
        const std::string config = "threads=" + std::to_string(threads);
        m_device = rtcNewDevice(config.c_str());
        if (!m_device)
            throw Error("Embree: rtcNewDevice failed (error " + std::to_string(rtcGetDeviceError(nullptr)) +
                        ")");
        m_scene = rtcNewScene(m_device);
        rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_HIGH);
        m_models.reserve(rs.models().size());
        for (std::size_t mi = 0; mi < rs.models().size(); ++mi) {
            const rt::LoadedModel& lm = rs.models()[mi];
            const char* who = "prt-bench-embree (the points of the pool)";
            const auto pos = lm.pool->require<pool::Float3>(pool::SectionType::positions, who);
            const auto nrm = lm.pool->require<pool::Float3>(pool::SectionType::normals, who);
            const auto rad = lm.pool->require<float>(pool::SectionType::radii, who);
            if (pos.size() != nrm.size() || pos.size() != rad.size())
                throw Error(lm.pool->label() + ": positions, normals and radii differ in count");
            const core::ModelView& v = lm.view;
            auto& dm = m_models.emplace_back(std::make_unique<DiscModel>());
            dm->model = static_cast<std::uint32_t>(mi);
            dm->normals.resize(pos.size() * 3);
            RTCGeometry g = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT);
            auto* vb = static_cast<float*>(
                rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 16, pos.size()));
            auto* nb = static_cast<float*>(
                rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_NORMAL, 0, RTC_FORMAT_FLOAT3, 12, pos.size()));
            if (!vb || !nb) throw Error("Embree: cannot allocate the disc buffers");
            for (std::size_t i = 0; i < pos.size(); ++i) {
                // render = rotation * (scale * local) + offset, as core::to_model_frame inverts.
                const core::Vec3 p = v.rotation * (core::vec3(pos[i]) * v.scale) + v.offset;
                const core::Vec3 n = core::normalize_or(v.rotation * core::vec3(nrm[i]), core::Vec3{0, 0, 1});
                vb[4 * i + 0] = p.x;
                vb[4 * i + 1] = p.y;
                vb[4 * i + 2] = p.z;
                vb[4 * i + 3] = rad[i] * v.scale;
                nb[3 * i + 0] = dm->normals[3 * i + 0] = n.x;
                nb[3 * i + 1] = dm->normals[3 * i + 1] = n.y;
                nb[3 * i + 2] = dm->normals[3 * i + 2] = n.z;
            }
            rtcSetGeometryUserData(g, dm.get());
            rtcSetGeometryIntersectFilterFunction(g, seamless_filter);
            rtcSetGeometryOccludedFilterFunction(g, seamless_filter);
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(m_scene, g, static_cast<unsigned>(mi));
            rtcReleaseGeometry(g);
            m_discs += pos.size();
        }
        const double t0 = tool::now_seconds();
        rtcCommitScene(m_scene);
        m_build_seconds = tool::now_seconds() - t0;
        if (rtcGetDeviceError(m_device) != RTC_ERROR_NONE)
            throw Error("Embree: building the scene failed (error " +
                        std::to_string(rtcGetDeviceError(m_device)) + ")");
    }
    ~EmbreeScene() {
        if (m_scene) rtcReleaseScene(m_scene);
        if (m_device) rtcReleaseDevice(m_device);
    }
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    RTCScene scene() const { return m_scene; }
    const DiscModel& model(unsigned geom) const { return *m_models[geom]; }
    std::uint64_t discs() const { return m_discs; }
    double build_seconds() const { return m_build_seconds; }

private:
    RTCDevice m_device = nullptr;
    RTCScene m_scene = nullptr;
    std::vector<std::unique_ptr<DiscModel>> m_models;
    std::uint64_t m_discs = 0;
    double m_build_seconds = 0;
};

/// The core's trace_ray (render.h) with Embree answering the closest-hit and any-hit queries.
class EmbreeTracer {
public:
    EmbreeTracer(const EmbreeScene& es, const core::SceneView& view) : m_es(es), m_view(view) {}

    const core::SceneView& view() const { return m_view; }

    /// Nearest disc along the ray in [0, t_max): the core's SurfaceHit (no blending).
    bool closest(const core::Ray& r, core::SurfaceHit& hit) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh{};
        set_ray(rh.ray, r, r.t_max);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(m_es.scene(), &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
        const DiscModel& dm = m_es.model(rh.hit.geomID);
        const core::ModelView& mv = m_view.models[dm.model];
        const std::uint32_t point = rh.hit.primID;
        const float* n = dm.normals.data() + 3 * static_cast<std::size_t>(point);
        // Material and color as core::closest_hit_scene picks them, from the nearest disc.
        const std::uint32_t mat = core::hit_material(m_view, mv, point);
        hit.t = rh.ray.tfar;
        hit.position = core::ray_at(r, hit.t);
        hit.normal = core::Vec3{n[0], n[1], n[2]};
        hit.material = mat;
        hit.model = dm.model;
        const bool colors =
            mv.colors != nullptr && m_view.material_count > 0 && m_view.materials[mat].use_point_colors != 0;
        hit.base_color = colors ? core::srgb_to_linear(core::OctreeSplats{nullptr, mv.colors}.color(point))
                                : core::Vec3{1, 1, 1};
        return true;
    }

    /// Whether a disc blocks [0, r.t_max) (core::occluded).
    bool occluded(const core::Ray& r) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRay ray{};
        set_ray(ray, r, std::nextafter(r.t_max, 0.0f));
        rtcOccluded1(m_es.scene(), &ctx, &ray);
        return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
    }

    /// core::trace_ray's queries (render.h SceneTracer) answered by Embree: its nearest disc, and
    /// core::shade_hit with Embree's shadow rays.
    bool closest(const core::SceneView&, const core::PendingRay& p, core::SurfaceHit& h,
                 core::RayCounters&) const {
        return closest(p.ray, h);
    }
    core::Vec3 shade(const core::SceneView& s, const core::PendingRay& p, const core::SurfaceHit& h,
                     core::RayCounters& c) const {
        return core::shade_hit(
            s, p.ray, h, c,
            [this](const core::SceneView&, const core::Ray& r, core::RayCounters&) { return occluded(r); });
    }

private:
    static void set_ray(RTCRay& ray, const core::Ray& r, float tfar) {
        ray.org_x = r.origin.x;
        ray.org_y = r.origin.y;
        ray.org_z = r.origin.z;
        ray.tnear = 0.0f;  // thesis 3.6: no minimum distance, the filter keeps a ray off its surface
        ray.dir_x = r.dir.x;
        ray.dir_y = r.dir.y;
        ray.dir_z = r.dir.z;
        ray.time = 0.0f;
        ray.tfar = std::isfinite(tfar) ? tfar : std::numeric_limits<float>::infinity();
        ray.mask = 0xffffffffu;
        ray.id = r.flags;
        ray.flags = 0;
    }

    const EmbreeScene& m_es;
    const core::SceneView& m_view;
};

/// Renders every pixel over `threads` threads in 16x16 tiles, like the CPU backend.
rt::FrameStats render_embree(const EmbreeTracer& tracer, const core::PinholeCamera& cam,
                             const core::RenderParams& p, std::uint32_t w, std::uint32_t h, unsigned threads,
                             rt::Image& image) {
    const double t0 = tool::now_seconds();
    image.resize(w, h);
    const std::uint32_t tiles_x = (w + k_tile - 1) / k_tile, tiles = tiles_x * ((h + k_tile - 1) / k_tile);
    std::atomic<std::uint32_t> next{0};
    std::vector<core::RayCounters> counters(threads);
    auto job = [&](unsigned worker) {
        core::RayCounters& c = counters[worker];
        for (;;) {
            const std::uint32_t t = next.fetch_add(1);
            if (t >= tiles) break;
            const std::uint32_t x0 = (t % tiles_x) * k_tile, y0 = (t / tiles_x) * k_tile;
            for (std::uint32_t y = y0; y < std::min(y0 + k_tile, h); ++y) {
                for (std::uint32_t x = x0; x < std::min(x0 + k_tile, w); ++x) {
                    const core::Vec3 color = core::sanitize(
                        core::trace_ray(tracer.view(), core::primary_ray(cam, x, y, w, h), c, tracer), c);
                    const std::size_t i = static_cast<std::size_t>(y) * w + x;
                    image.rgb[i * 3 + 0] = color.x;
                    image.rgb[i * 3 + 1] = color.y;
                    image.rgb[i * 3 + 2] = color.z;
                    image.rgba8[i] = core::pack_rgba8(core::encode_display(color, p));
                }
            }
        }
    };
    std::vector<std::thread> pool;
    for (unsigned i = 1; i < threads; ++i) pool.emplace_back(job, i);
    job(0);
    for (std::thread& t : pool) t.join();
    rt::FrameStats s;
    for (const core::RayCounters& c : counters) s += c;
    s.pixels = static_cast<std::uint64_t>(w) * h;
    s.seconds = tool::now_seconds() - t0;
    return s;
}

/// Both renderers' frame times, frame by frame.
struct PairedTimes {
    double a = 0, b = 0;  ///< median frame time (seconds) of each
    double ratio = 0;     ///< median over the frame pairs of b's time / a's
};

/// `frames` frames of `a` and of `b` after `warmup` of each, in turns (a, b, a, b, ...), so a
/// machine that slows down or speeds up during the run (a shared VM) moves both alike and the
/// ratio of a pair's times stays the comparison; the last frame's stats of each.
PairedTimes time_paired(std::uint32_t warmup, std::uint32_t frames, const std::function<rt::FrameStats()>& a,
                        const std::function<rt::FrameStats()>& b, rt::FrameStats& last_a,
                        rt::FrameStats& last_b) {
    for (std::uint32_t i = 0; i < warmup; ++i) {
        a();
        b();
    }
    std::vector<double> ta, tb, r;
    for (std::uint32_t i = 0; i < frames; ++i) {
        last_a = a();
        last_b = b();
        ta.push_back(last_a.seconds);
        tb.push_back(last_b.seconds);
        r.push_back(last_b.seconds / std::max(last_a.seconds, 1e-12));
    }
    return PairedTimes{player::median(ta), player::median(tb), player::median(r)};
}

void run(const Options& o, const tool::CommonOptions& common) {
    const unsigned threads = o.threads ? o.threads : prt::available_cores();
    rt::RenderScene rs = player::bench_scene(o.scene, common.quiet);
    core::RenderParams base = rs.params();
    player::apply(o.render, base);
    const EmbreeScene es(rs, threads);
    rt::BackendOptions bo;
    bo.cpu_threads = threads;
    auto ours = rt::make_backend("cpu", bo);
    std::uint64_t splats = 0;
    for (const auto& m : rs.models()) splats += m.view.octree.splat_count;
    std::printf(
        "prt-bench-embree: %ux%u, %u threads (%s); ours: %llu stored splats (octree, replicas included); "
        "Embree "
        "%d.%d.%d: %llu oriented discs (one per point), BVH build %.2f s\n",
        o.scene.width, o.scene.height, threads, ours->device().c_str(),
        static_cast<unsigned long long>(splats), RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH,
        static_cast<unsigned long long>(es.discs()), es.build_seconds());
    std::printf("%-10s %12s %12s %14s %14s %12s %10s\n", "scenario", "ours ms", "Embree ms", "ours Mrays/s",
                "Embree Mrays/s", "ours/Embree", "img diff");
    nlohmann::json report;
    report["width"] = o.scene.width;
    report["height"] = o.scene.height;
    report["threads"] = threads;
    report["ours"] = {{"backend", ours->device()}, {"stored_splats", splats}};
    report["embree"] = {
        {"version", std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
                        std::to_string(RTC_VERSION_PATCH)},
        {"discs", es.discs()},
        {"build_seconds", es.build_seconds()}};
    const std::vector<core::Material> original(rs.view().materials,
                                               rs.view().materials + rs.view().material_count);
    const core::PinholeCamera cam = rs.camera();
    const std::uint32_t w = o.scene.width, h = o.scene.height;
    for (const player::BenchScenario& sc : player::bench_scenarios(base)) {
        if (o.scenarios.find(sc.name) == std::string::npos) continue;
        const std::vector<core::Material> mats = player::scenario_materials(sc, original);
        core::SceneView view = rs.view();
        view.materials = mats.data();
        view.params = sc.params;
        ours->set_scene(view);
        rt::FrameRequest req;
        req.camera = cam;
        req.params = sc.params;
        req.width = w;
        req.height = h;
        rt::Image ours_img, embree_img;
        rt::FrameStats ours_last, embree_last;
        const EmbreeTracer tracer(es, view);
        const PairedTimes pt = time_paired(
            o.warmup, o.frames, [&] { return ours->render(req, ours_img); },
            [&] { return render_embree(tracer, cam, sc.params, w, h, threads, embree_img); }, ours_last,
            embree_last);
        const double ours_s = pt.a, embree_s = pt.b;
        double diff = 0;
        for (std::size_t i = 0; i < ours_img.rgba8.size(); ++i)
            for (int c = 0; c < 3; ++c)
                diff += std::abs(static_cast<int>((ours_img.rgba8[i] >> (8 * c)) & 0xffu) -
                                 static_cast<int>((embree_img.rgba8[i] >> (8 * c)) & 0xffu));
        diff /= 3.0 * std::max<std::size_t>(1, ours_img.rgba8.size());
        const double ours_rate = ours_last.rays() / ours_s * 1e-6,
                     embree_rate = embree_last.rays() / embree_s * 1e-6;
        // ours / Embree in rays per second: the median pair's time ratio, scaled by the ray counts
        // (the same rays but for the blending's secondary-ray differences).
        const double ratio = pt.ratio * static_cast<double>(ours_last.rays()) /
                             static_cast<double>(std::max<std::uint64_t>(embree_last.rays(), 1));
        std::printf("%-10s %12.1f %12.1f %14.2f %14.2f %12.2f %10.2f\n", sc.name.c_str(), ours_s * 1e3,
                    embree_s * 1e3, ours_rate, embree_rate, ratio, diff);
        report["scenarios"].push_back({{"name", sc.name},
                                       {"ours_ms", ours_s * 1e3},
                                       {"embree_ms", embree_s * 1e3},
                                       {"ours_rays", ours_last.rays()},
                                       {"embree_rays", embree_last.rays()},
                                       {"ours_mrays_per_s", ours_rate},
                                       {"embree_mrays_per_s", embree_rate},
                                       {"ratio_ours_over_embree", ratio},
                                       {"mean_abs_diff_8bit", diff}});
    }
    // The same surface: primary hit distances of both, on every 4th pixel in each direction.
    std::uint64_t both = 0, agree = 0, only_ours = 0, only_embree = 0;
    {
        core::SceneView view = rs.view();
        view.params = base;
        const EmbreeTracer tracer(es, view);
        for (std::uint32_t y = 0; y < h; y += 4) {
            for (std::uint32_t x = 0; x < w; x += 4) {
                const core::Ray r = core::primary_ray(cam, x, y, w, h);
                core::SurfaceHit a, b;
                core::RayCounters c;
                const bool ha = core::closest_hit_scene(view, r, a, c), hb = tracer.closest(r, b);
                if (ha && hb) {
                    ++both;
                    // Within the blending window of one splat radius (the radius of the room's disks).
                    const float radius = rs.models()[0].pool->array<float>(pool::SectionType::radii)[0];
                    agree += std::abs(a.t - b.t) <= 2.0f * radius;
                } else {
                    only_ours += ha && !hb;
                    only_embree += hb && !ha;
                }
            }
        }
    }
    std::printf(
        "primary hits compared on every 16th pixel: both hit %llu, same distance (within 2 splat radii) "
        "%.2f%%, only ours %llu, only Embree %llu\n",
        static_cast<unsigned long long>(both), both ? 100.0 * agree / both : 0.0,
        static_cast<unsigned long long>(only_ours), static_cast<unsigned long long>(only_embree));
    report["primary_agreement"] = {
        {"both_hit", both}, {"same_distance", agree}, {"only_ours", only_ours}, {"only_embree", only_embree}};
    if (!o.json.empty()) {
        std::ofstream f(o.json);
        if (!f) throw Error(o.json + ": cannot write");
        f << report.dump(2) << "\n";
        if (!f) throw Error(o.json + ": write failed");
    }
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    o.scene.width = 512;
    o.scene.height = 512;
    return prt::tool::run(
        argc, argv, "prt-bench-embree",
        "CPU peer benchmark: the same splats and view as prt-bench (default: the synthetic room of "
        "--synthetic "
        "points), rendered by PointRT's CPU backend (octree, blended splats) and by Embree 3 (one oriented "
        "disc "
        "per point, rtcIntersect1 with the seamless front/back filter of thesis 3.6), both on --threads "
        "threads. Prints frame times, rays per second and ours / Embree per scenario.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            player::add_scene_options(app, o.scene,
                                      "Pool with points, radii and octree (default: the synthetic room)",
                                      "Synthetic room: our octree's splats per leaf", false);
            app.add_option("--frames", o.frames,
                           "Timed frames per scenario and renderer (the median is reported)")
                ->check(CLI::Range(1u, 100000u));
            app.add_option("--warmup", o.warmup, "Untimed frames before timing")
                ->check(CLI::Range(0u, 100000u));
            app.add_option("--threads", o.threads,
                           "Threads for both renderers (0: every core the process may use)");
            app.add_option("--scenarios", o.scenarios, "Comma-separated subset of primary,shadow,reflect4");
            app.add_option("--json", o.json, "Write the results as JSON to this file");
            prt::player::add_render_options(app, o.render);
        },
        [&](const prt::tool::CommonOptions& common) { run(o, common); });
}
