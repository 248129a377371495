// prt-fidelity (issue 15): how faithfully each surface of a pool reproduces a real reference, seen
// from several views, as a viewer would see it.
//
// The reference is a triangle mesh (the Stanford bunny's zippered reconstruction for its range
// scans; the mesh a sampled model came from) ray cast by independent code (mesh_reference.h: a
// plain BVH in double), or, for a prt-synth pool, the analytic shape of its provenance. The
// surfaces are traced through the core's own per-ray functions (surface_probe.h). Every distance is
// in units of the local point spacing s (point_spacing.h: sqrt(area per point) from the 8 nearest
// input points), so the figures mean the same at every scale and density.
//
// Per pixel of each view (a pinhole camera on the bounding sphere of the reference, aimed at its
// centre, directions spread over the sphere):
//   covered    the reference's first hit h is a front face, lies within C spacings of an input
//              point (C = --coverage, 2) and is surrounded by the input points within that distance
//              (projected on the reference's tangent plane, no angular gap of 180 degrees or more):
//              the scan has data there. A single range scan is judged only on the part it saw.
//              Back-face hits (looking into an open mesh) are not covered.
//   edge       within C spacings of an input point but outside the data's edge (not surrounded):
//              a surface may end there or go on; its misses are counted apart (edge holes, which
//              with the covered holes give the rate of the plain "within C spacings" rule).
//   hole       a covered pixel where the surface is missed, or hit more than F spacings (along
//              the reference normal) behind h: the ray went through (F = --tolerance, 2).
//   false hit  the surface is hit at x more than F spacings from the reference surface (any pixel).
//   good       the other covered pixels with a surface hit: depth error |t - t_ref| / s (along the
//              ray), surface distance |t - t_ref| |cos| / s (along the reference normal), normal
//              error (degrees between the traced normal and the reference's, oriented to the ray).
// Rates are per covered pixel. Images (--images DIR) show each view's reference and each surface,
// shaded, and a classification map: grey good, red holes, blue false hits, dark green covered by
// nothing (no data), orange missed at the data's edge, black background.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "analytic.h"
#include "mesh.h"
#include "mesh_reference.h"
#include "point_cloud.h"
#include "point_spacing.h"
#include "prt/atomic_file.h"
#include "prt/core/camera.h"
#include "prt/formats/pool.h"
#include "prt/parallel.h"
#include "prt/runtime/image.h"
#include "prt/tool.h"
#include "surface_probe.h"

namespace {

using namespace prt;
using bench::D3;

struct Options {
    std::string pool, reference, points, json, images, views_from = "orbit";
    std::vector<std::string> surfaces;
    std::uint32_t views = 6, width = 1024, height = 1024, threads = 0;
    float fov = 30.0f;
    double coverage = 2.0, tolerance = 2.0;
    bench::SurfaceSettings s;
};

// ---- the reference ------------------------------------------------------------------------------

/// The true surface: first hit along a ray (world frame, d unit) and distance from a point.
class Reference {
public:
    virtual ~Reference() = default;
    /// First hit: t, point, unit normal oriented as the surface is (outward), and whether the ray
    /// meets its front.
    virtual bool intersect(const D3& o, const D3& d, bench::MeshHit& hit) const = 0;
    virtual double distance(const D3& p) const = 0;
    virtual D3 lo() const = 0;
    virtual D3 hi() const = 0;
    virtual nlohmann::json describe() const = 0;
};

class MeshTruth final : public Reference {
public:
    explicit MeshTruth(const std::string& path) : m_path(path), m_mesh(load(path)) {}
    bool intersect(const D3& o, const D3& d, bench::MeshHit& hit) const override {
        return m_mesh.intersect(o, d, std::numeric_limits<double>::infinity(), hit);
    }
    double distance(const D3& p) const override { return m_mesh.distance(p); }
    D3 lo() const override { return m_mesh.bounds_min(); }
    D3 hi() const override { return m_mesh.bounds_max(); }
    nlohmann::json describe() const override {
        return {{"kind", "mesh"},
                {"path", m_path},
                {"triangles", m_mesh.triangle_count()},
                {"orientation_flipped", m_mesh.flipped()}};
    }

private:
    static bench::MeshReference load(const std::string& path) {
        pre::import::precheck_mesh_file(path);
        pre::import::Report report;
        const pre::import::MeshData m = pre::import::read_mesh(path, report, true);
        std::vector<std::array<std::uint32_t, 3>> tris;
        for (std::size_t f = 0; f < m.face_count(); ++f) {  // polygons as triangle fans
            const std::uint32_t b = m.face_begin[f], e = m.face_begin[f + 1];
            for (std::uint32_t k = b + 1; k + 1 < e; ++k)
                tris.push_back({m.face_indices[b], m.face_indices[k], m.face_indices[k + 1]});
        }
        try {
            return bench::MeshReference(m.vertices, std::move(tris));
        } catch (const Error& e) {
            throw Error(path + ": " + e.what());
        }
    }
    std::string m_path;
    bench::MeshReference m_mesh;
};

/// The analytic shape a prt-synth pool was sampled or scanned from (its provenance), ray cast
/// exactly (synth::first_hit, in double).
class AnalyticTruth final : public Reference {
public:
    explicit AnalyticTruth(const pool::PoolFile& p)
        : m_shape(synth::shape_from_provenance(p.provenance_json(), p.label())) {
        const auto b = synth::shape_bounds(m_shape);
        m_lo = b[0], m_hi = b[1];
    }
    bool intersect(const D3& o, const D3& d, bench::MeshHit& hit) const override {
        const auto h = synth::first_hit(m_shape, o, d);
        if (!h) return false;
        hit.t = h->t;
        hit.point = h->point;
        hit.normal = h->normal;
        hit.front = dot(h->normal, d) < 0;  // closest() orients normals to the side the points face
        return true;
    }
    double distance(const D3& p) const override {
        return std::abs(synth::closest(m_shape, p).signed_distance);
    }
    D3 lo() const override { return m_lo; }
    D3 hi() const override { return m_hi; }
    nlohmann::json describe() const override {
        return {{"kind", "analytic"}, {"shape", nlohmann::json::parse(synth::shape_to_json(m_shape))}};
    }

private:
    synth::Shape m_shape;
    D3 m_lo, m_hi;
};

// ---- views --------------------------------------------------------------------------------------

struct View {
    core::PinholeCamera camera;  ///< the pool's local frame
    D3 origin{};                 ///< world position of the local frame's origin
    D3 direction{};              ///< orbit: from the centre toward the eye; sensors: the face's direction
    D3 eye{};                    ///< world frame
    std::uint32_t width = 0, height = 0;
};

/// `count` directions spread over the sphere (a spherical Fibonacci set), turned so that none lies
/// along a coordinate axis (axis-aligned views make planes of scans exactly grazing).
std::vector<D3> view_directions(std::uint32_t count) {
    std::vector<D3> dirs;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (std::uint32_t i = 0; i < count; ++i) {
        const double y = 1.0 - (2.0 * i + 1.0) / count;
        const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
        const double phi = golden * i + 0.3;
        dirs.push_back({r * std::cos(phi), y * 0.96 + 0.02, r * std::sin(phi)});
        dirs.back() = mul(dirs.back(), 1.0 / length(dirs.back()));
    }
    return dirs;
}

View make_view(const Options& o, const D3& origin, const D3& lo, const D3& hi, const D3& dir) {
    const D3 centre = mul(add(lo, hi), 0.5);
    const double diag = length(sub(hi, lo));
    const double dist = 0.5 * diag / std::sin(0.5 * o.fov * M_PI / 180.0);
    const D3 eye = add(centre, mul(dir, dist));
    auto local = [&](const D3& a) {
        return core::Vec3{float(a[0] - origin[0]), float(a[1] - origin[1]), float(a[2] - origin[2])};
    };
    View v;
    v.origin = origin;
    v.direction = dir;
    v.eye = eye;
    v.width = o.width;
    v.height = o.height;
    const core::Vec3 up = std::abs(dir[1]) > 0.95 ? core::Vec3{0, 0, 1} : core::Vec3{0, 1, 0};
    v.camera = core::make_pinhole(local(eye), local(centre), up, o.fov, o.width, o.height);
    return v;
}

/// The six faces of a cube map around each point sensor (fov 90): what the scanner saw, from where
/// it stood (a room scanned from inside cannot be seen from outside).
std::vector<View> sensor_views(const Options& o, const pool::PoolFile& p, const D3& origin) {
    std::vector<View> views;
    for (const pool::Sensor& s : p.array<pool::Sensor>(pool::SectionType::sensors)) {
        if (s.kind != pool::k_sensor_point) continue;
        const D3 eye{s.position[0], s.position[1], s.position[2]};
        for (const D3& dir :
             {D3{1, 0, 0}, D3{-1, 0, 0}, D3{0, 1, 0}, D3{0, -1, 0}, D3{0, 0, 1}, D3{0, 0, -1}}) {
            auto local = [&](const D3& a) {
                return core::Vec3{float(a[0] - origin[0]), float(a[1] - origin[1]), float(a[2] - origin[2])};
            };
            View v;
            v.origin = origin;
            v.direction = dir;
            v.eye = eye;
            v.width = o.width;
            v.height = o.height;
            const core::Vec3 up = std::abs(dir[1]) > 0.5 ? core::Vec3{0, 0, 1} : core::Vec3{0, 1, 0};
            v.camera = core::make_pinhole(local(eye), local(add(eye, dir)), up, 90.0f, o.width, o.height);
            views.push_back(v);
        }
    }
    if (views.empty())
        throw Error(o.pool + ": --views-from sensors: the pool has no point sensor (section sensors)");
    return views;
}

// ---- per-pixel results --------------------------------------------------------------------------

enum class RefClass : std::uint8_t { background, back_face, uncovered, edge, covered };
enum class PixClass : std::uint8_t { none, good, hole, false_hit, edge_hole };

struct RefPixel {
    RefClass cls = RefClass::background;
    double t = 0;
    D3 point{}, normal{};  ///< normal oriented toward the ray
    double spacing = 0;    ///< local spacing at the hit (nearest input point's)
};

struct SurfPixel {
    bool hit = false;
    float t = 0;
    core::Vec3 normal{0, 0, 1};
};

/// Mean, median, p90 and max of a sample.
nlohmann::json summary(std::vector<float> v) {
    if (v.empty()) return nullptr;
    std::sort(v.begin(), v.end());
    double sum = 0;
    for (float x : v) sum += x;
    auto q = [&](double f) { return double(v[std::min(v.size() - 1, std::size_t(f * double(v.size())))]); };
    return {{"mean", sum / double(v.size())},
            {"median", q(0.5)},
            {"p90", q(0.9)},
            {"max", double(v.back())},
            {"count", v.size()}};
}

struct Tally {
    std::uint64_t covered = 0, holes = 0, false_hits = 0, good = 0, hits = 0, edge = 0, edge_holes = 0;
    std::vector<float> depth, distance, normal_deg;
    double seconds = 0;
    std::uint64_t rays = 0;
    void merge(const Tally& t) {
        covered += t.covered, holes += t.holes, false_hits += t.false_hits, good += t.good, hits += t.hits;
        edge += t.edge, edge_holes += t.edge_holes;
        depth.insert(depth.end(), t.depth.begin(), t.depth.end());
        distance.insert(distance.end(), t.distance.begin(), t.distance.end());
        normal_deg.insert(normal_deg.end(), t.normal_deg.begin(), t.normal_deg.end());
        seconds += t.seconds, rays += t.rays;
    }
    nlohmann::json json(bool with_samples) const {
        nlohmann::json j = {{"covered_pixels", covered},
                            {"surface_hits", hits},
                            {"holes", holes},
                            {"false_hits", false_hits},
                            {"good", good},
                            {"hole_rate", covered ? double(holes) / double(covered) : 0.0},
                            {"false_hit_rate", covered ? double(false_hits) / double(covered) : 0.0},
                            {"edge_pixels", edge},
                            {"edge_holes", edge_holes},
                            {"hole_rate_with_edges",
                             covered + edge ? double(holes + edge_holes) / double(covered + edge) : 0.0}};
        if (with_samples) {
            j["depth_error_spacings"] = summary(depth);
            j["surface_distance_spacings"] = summary(distance);
            j["normal_error_degrees"] = summary(normal_deg);
            j["rays_per_s"] = seconds > 0 ? double(rays) / seconds : 0.0;
        }
        return j;
    }
};

std::uint32_t pack(double r, double g, double b) {
    auto c = [](double v) { return std::uint32_t(std::lround(std::clamp(v, 0.0, 1.0) * 255)); };
    return c(r) | (c(g) << 8) | (c(b) << 16) | (0xffu << 24);
}

void write_rgba(const std::filesystem::path& path, std::uint32_t w, std::uint32_t h,
                const std::vector<std::uint32_t>& px) {
    rt::Image img;
    img.resize(w, h);
    img.rgba8 = px;
    for (std::size_t i = 0; i < px.size(); ++i)
        for (int k = 0; k < 3; ++k)
            img.rgb[3 * i + k] = std::pow(float((px[i] >> (8 * k)) & 0xffu) / 255.f, 2.2f);
    rt::write_image(path, img);
}

/// Whether h is surrounded by the input points within `radius` (k-NN, at most 16): projected on the
/// plane of normal n, they leave no angular gap of pi or more around h, so h is inside the data, not
/// past its edge.
bool surrounded(const bench::PointIndex& index, const D3& h, const D3& n, double radius,
                std::vector<std::uint32_t>& idx, std::vector<double>& angles) {
    index.knn_indices(h, 16, idx);
    // a basis of the tangent plane
    const D3 a = std::abs(n[0]) < 0.9 ? D3{1, 0, 0} : D3{0, 1, 0};
    D3 u{a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2], a[0] * n[1] - a[1] * n[0]};
    u = mul(u, 1.0 / length(u));
    const D3 v{n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
    angles.clear();
    for (std::uint32_t i : idx) {
        const D3 e = sub(index.point(i), h);
        if (dot(e, e) > radius * radius) break;
        const double x = dot(e, u), y = dot(e, v);
        if (x * x + y * y > 0) angles.push_back(std::atan2(y, x));
    }
    if (angles.size() < 3) return false;
    std::sort(angles.begin(), angles.end());
    double gap = angles.front() + 2 * M_PI - angles.back();
    for (std::size_t i = 1; i < angles.size(); ++i) gap = std::max(gap, angles[i] - angles[i - 1]);
    return gap < M_PI;
}

/// Headlight Lambert grey of a normal seen along d.
double shade(const D3& n, const D3& d) {
    return 0.12 + 0.85 * std::abs(dot(n, d));
}

// ---- the measurement ----------------------------------------------------------------------------

void fidelity(Options o, const tool::CommonOptions& common) {
    auto shared = std::make_shared<const pool::PoolFile>(pool::PoolFile::open(o.pool));
    const pool::PoolFile& p = *shared;
    const pool::ModelInfo& mi = p.model_info();
    const D3 origin{mi.origin[0], mi.origin[1], mi.origin[2]};
    const unsigned threads = resolve_threads(o.threads);

    // Surfaces: the ones asked for, or every one the pool holds.
    if (o.surfaces.empty()) {
        if (p.has(pool::SectionType::splats)) o.surfaces.push_back("splats");
        if (p.has(pool::SectionType::iso_info)) o.surfaces.push_back("iso");
        if (p.has(pool::SectionType::mls_info)) o.surfaces.push_back("mls");
        if (o.surfaces.empty())
            throw Error(o.pool + ": holds no surface (run prt-octree, prt-iso or prt-mls)");
    }
    std::vector<std::unique_ptr<bench::SurfaceProbe>> probes;
    for (const std::string& s : o.surfaces)
        probes.push_back(std::make_unique<bench::SurfaceProbe>(shared, s, o.s));

    // The input points: where the scan has data, and its local spacing.
    const double t_start = tool::now_seconds();
    std::vector<D3> pts;
    {
        std::unique_ptr<pool::PoolFile> other;
        if (!o.points.empty()) other = std::make_unique<pool::PoolFile>(pool::PoolFile::open(o.points));
        const pre::PointCloud cloud = pre::read_point_sections(other ? *other : p);
        pts = cloud.positions;
    }
    if (pts.size() < 16) throw Error((o.points.empty() ? o.pool : o.points) + ": fewer than 16 points");
    const bench::PointIndex index(pts);
    const std::vector<double> spacing = index.local_spacing(threads);
    std::vector<double> sorted_spacing = spacing;
    std::sort(sorted_spacing.begin(), sorted_spacing.end());

    std::unique_ptr<Reference> truth;
    if (!o.reference.empty()) {
        truth = std::make_unique<MeshTruth>(o.reference);
    } else {
        try {
            truth = std::make_unique<AnalyticTruth>(p);
        } catch (const Error&) {
            throw Error(o.pool +
                        ": no reference: give --reference MESH, or a pool made by prt-synth (its "
                        "provenance names the analytic shape)");
        }
    }
    tool::note(common.quiet, "prt-fidelity: %zu input points (median spacing %.4g), reference %s, %.2f s",
               pts.size(), sorted_spacing[sorted_spacing.size() / 2], truth->describe().dump().c_str(),
               tool::now_seconds() - t_start);

    std::vector<View> views;
    if (o.views_from == "sensors") {
        views = sensor_views(o, p, origin);
    } else {
        for (const D3& d : view_directions(o.views))
            views.push_back(make_view(o, origin, truth->lo(), truth->hi(), d));
    }
    std::vector<Tally> totals(probes.size());
    nlohmann::json per_view = nlohmann::json::array();
    std::uint64_t ref_covered = 0, ref_uncovered = 0, ref_back = 0, ref_pixels = 0, ref_edge = 0;
    const std::size_t npx = std::size_t(o.width) * o.height;
    if (!o.images.empty()) std::filesystem::create_directories(o.images);
    tool::Progress progress("prt-fidelity: views", views.size(), common.quiet);

    for (std::uint32_t vi = 0; vi < views.size(); ++vi) {
        const View& view = views[vi];
        auto world_ray = [&](std::uint32_t x, std::uint32_t y, D3& wo, D3& wd) {
            const core::Ray r = core::primary_ray(view.camera, x, y, view.width, view.height);
            wo = add(origin, D3{r.origin.x, r.origin.y, r.origin.z});
            wd = D3{r.dir.x, r.dir.y, r.dir.z};
            return r;
        };
        // Reference pass.
        std::vector<RefPixel> ref(npx);
        parallel_chunks(o.height, 1, threads, [&](std::size_t y0, std::size_t y1, unsigned) {
            std::vector<std::uint32_t> idx;
            std::vector<double> angles;
            for (std::size_t y = y0; y < y1; ++y)
                for (std::uint32_t x = 0; x < o.width; ++x) {
                    D3 wo, wd;
                    world_ray(x, std::uint32_t(y), wo, wd);
                    RefPixel& r = ref[y * o.width + x];
                    bench::MeshHit h;
                    if (!truth->intersect(wo, wd, h)) continue;
                    r.t = h.t;
                    r.point = h.point;
                    r.normal = dot(h.normal, wd) < 0 ? h.normal : mul(h.normal, -1.0);
                    if (!h.front) {
                        r.cls = RefClass::back_face;
                        continue;
                    }
                    double d;
                    const std::uint32_t ni = index.nearest(h.point, d);
                    r.spacing = spacing[ni];
                    if (d > o.coverage * r.spacing)
                        r.cls = RefClass::uncovered;
                    else if (surrounded(index, h.point, r.normal, o.coverage * r.spacing, idx, angles))
                        r.cls = RefClass::covered;
                    else
                        r.cls = RefClass::edge;
                }
        });
        std::uint64_t covered = 0;
        for (const RefPixel& r : ref) {
            ref_pixels += r.cls != RefClass::background;
            covered += r.cls == RefClass::covered;
            ref_edge += r.cls == RefClass::edge;
            ref_uncovered += r.cls == RefClass::uncovered;
            ref_back += r.cls == RefClass::back_face;
        }
        ref_covered += covered;
        nlohmann::json vj = {{"direction", view.direction},
                             {"eye", view.eye},
                             {"covered_pixels", covered},
                             {"surfaces", nlohmann::json::object()}};
        if (!o.images.empty()) {
            std::vector<std::uint32_t> img(npx, pack(0, 0, 0));
            for (std::uint32_t y = 0; y < o.height; ++y)
                for (std::uint32_t x = 0; x < o.width; ++x) {
                    const RefPixel& r = ref[std::size_t(y) * o.width + x];
                    D3 wo, wd;
                    world_ray(x, y, wo, wd);
                    const double g = shade(r.normal, wd);
                    if (r.cls == RefClass::covered) img[std::size_t(y) * o.width + x] = pack(g, g, g);
                    if (r.cls == RefClass::uncovered)
                        img[std::size_t(y) * o.width + x] = pack(0.2 * g, 0.45 * g, 0.2 * g);
                    if (r.cls == RefClass::back_face)
                        img[std::size_t(y) * o.width + x] = pack(0.4 * g, 0.3 * g, 0.1 * g);
                    if (r.cls == RefClass::edge)
                        img[std::size_t(y) * o.width + x] = pack(0.9 * g, 0.6 * g, 0.2 * g);
                }
            write_rgba(std::filesystem::path(o.images) / ("reference_view" + std::to_string(vi) + ".png"),
                       o.width, o.height, img);
        }

        for (std::size_t si = 0; si < probes.size(); ++si) {
            const bench::SurfaceProbe& probe = *probes[si];
            std::vector<SurfPixel> surf(npx);
            const double t0 = tool::now_seconds();
            parallel_chunks(o.height, 1, threads, [&](std::size_t y0, std::size_t y1, unsigned) {
                for (std::size_t y = y0; y < y1; ++y)
                    for (std::uint32_t x = 0; x < o.width; ++x) {
                        const core::Ray r =
                            core::primary_ray(view.camera, x, std::uint32_t(y), view.width, view.height);
                        bench::ProbeHit h;
                        SurfPixel& s = surf[y * o.width + x];
                        if (probe.trace(r, h)) s.hit = true, s.t = float(h.t), s.normal = h.normal;
                    }
            });
            const double secs = tool::now_seconds() - t0;
            // Classification (per row, then merged).
            std::vector<Tally> rows(o.height);
            std::vector<PixClass> cls(npx, PixClass::none);
            parallel_chunks(o.height, 1, threads, [&](std::size_t y0, std::size_t y1, unsigned) {
                for (std::size_t y = y0; y < y1; ++y) {
                    Tally& t = rows[y];
                    for (std::uint32_t x = 0; x < o.width; ++x) {
                        const std::size_t i = y * o.width + x;
                        const RefPixel& r = ref[i];
                        const SurfPixel& s = surf[i];
                        D3 wo, wd;
                        world_ray(x, std::uint32_t(y), wo, wd);
                        const bool is_covered = r.cls == RefClass::covered;
                        t.covered += is_covered;
                        t.edge += r.cls == RefClass::edge;
                        if (!s.hit) {
                            if (is_covered) ++t.holes, cls[i] = PixClass::hole;
                            if (r.cls == RefClass::edge) ++t.edge_holes, cls[i] = PixClass::edge_hole;
                            continue;
                        }
                        ++t.hits;
                        const D3 xw = add(wo, mul(wd, double(s.t)));
                        double dn;
                        const double sx = spacing[index.nearest(xw, dn)];
                        // False hit: farther than F spacings from the reference surface. Near the
                        // reference hit, that distance is bounded by |x - h| without a query.
                        const bool near_ref =
                            r.cls != RefClass::background && length(sub(xw, r.point)) <= o.tolerance * sx;
                        if (!near_ref && truth->distance(xw) > o.tolerance * sx) {
                            ++t.false_hits, cls[i] = PixClass::false_hit;
                            continue;
                        }
                        if (!is_covered) {
                            if (r.cls == RefClass::edge &&
                                (double(s.t) - r.t) * std::abs(dot(r.normal, wd)) > o.tolerance * r.spacing)
                                ++t.edge_holes, cls[i] = PixClass::edge_hole;
                            continue;
                        }
                        const double cosr = std::abs(dot(r.normal, wd));
                        const double behind = (double(s.t) - r.t) * cosr;
                        if (behind > o.tolerance * r.spacing) {
                            ++t.holes, cls[i] = PixClass::hole;
                            continue;
                        }
                        ++t.good, cls[i] = PixClass::good;
                        t.depth.push_back(float(std::abs(double(s.t) - r.t) / r.spacing));
                        t.distance.push_back(float(std::abs(double(s.t) - r.t) * cosr / r.spacing));
                        const D3 n{s.normal.x, s.normal.y, s.normal.z};
                        const double c = std::clamp(dot(n, r.normal) / std::max(1e-30, length(n)), -1.0, 1.0);
                        t.normal_deg.push_back(float(std::acos(c) * 180.0 / M_PI));
                    }
                }
            });
            Tally view_tally;
            for (const Tally& t : rows) view_tally.merge(t);
            view_tally.seconds = secs;
            view_tally.rays = npx;
            vj["surfaces"][probe.surface()] = view_tally.json(false);
            totals[si].merge(view_tally);
            if (!o.images.empty()) {
                std::vector<std::uint32_t> shaded(npx, pack(0, 0, 0)), map(npx, pack(0, 0, 0));
                for (std::uint32_t y = 0; y < o.height; ++y)
                    for (std::uint32_t x = 0; x < o.width; ++x) {
                        const std::size_t i = std::size_t(y) * o.width + x;
                        D3 wo, wd;
                        world_ray(x, y, wo, wd);
                        const SurfPixel& s = surf[i];
                        const double g = s.hit ? shade(D3{s.normal.x, s.normal.y, s.normal.z}, wd) : 0.0;
                        if (s.hit) shaded[i] = pack(g, g, g);
                        switch (cls[i]) {
                            case PixClass::good:
                                map[i] = pack(g, g, g);
                                break;
                            case PixClass::hole:
                                map[i] = pack(1, 0.1, 0.1);
                                break;
                            case PixClass::false_hit:
                                map[i] = pack(0.15, 0.35, 1);
                                break;
                            case PixClass::edge_hole:
                                map[i] = pack(1, 0.6, 0.1);
                                break;
                            case PixClass::none:
                                if (ref[i].cls == RefClass::uncovered || ref[i].cls == RefClass::back_face)
                                    map[i] = pack(0.05, 0.25, 0.05);
                                else if (s.hit)
                                    map[i] = pack(0.5 * g, 0.5 * g, 0.5 * g);
                                break;
                        }
                    }
                const std::string stem = probe.surface() + "_view" + std::to_string(vi);
                write_rgba(std::filesystem::path(o.images) / (stem + ".png"), o.width, o.height, shaded);
                write_rgba(std::filesystem::path(o.images) / (stem + "_class.png"), o.width, o.height, map);
            }
        }
        per_view.push_back(vj);
        progress.update(vi + 1);
    }
    progress.finish();

    nlohmann::json j;
    j["pool"] = o.pool;
    j["points"] = o.points.empty() ? o.pool : o.points;
    j["reference"] = truth->describe();
    j["views"] = views.size();
    j["views_from"] = o.views_from;
    j["width"] = o.width;
    j["height"] = o.height;
    j["fov_degrees"] = o.fov;
    j["coverage_spacings"] = o.coverage;
    j["tolerance_spacings"] = o.tolerance;
    j["threads"] = threads;
    j["input_points"] = pts.size();
    {
        // The data itself against the reference: how far the input points lie from it, in their
        // own spacings (noise, misregistration, outliers the import kept).
        std::vector<float> off(pts.size());
        parallel_chunks(pts.size(), 4096, threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t i = b; i < e; ++i)
                off[i] = float(truth->distance(pts[i]) / std::max(spacing[i], 1e-300));
        });
        std::uint64_t far = 0;
        for (float d : off) far += d > o.tolerance;
        j["input_offset_spacings"] = summary(off);
        j["input_points_beyond_tolerance"] = far;
    }
    j["spacing"] = {{"median", sorted_spacing[sorted_spacing.size() / 2]},
                    {"p10", sorted_spacing[sorted_spacing.size() / 10]},
                    {"p90", sorted_spacing[sorted_spacing.size() * 9 / 10]}};
    j["reference_pixels"] = {{"covered", ref_covered},
                             {"edge", ref_edge},
                             {"uncovered", ref_uncovered},
                             {"back_face", ref_back},
                             {"total", ref_pixels}};
    for (std::size_t si = 0; si < probes.size(); ++si) {
        nlohmann::json sj = totals[si].json(true);
        sj["settings"] = probes[si]->settings();
        sj["surface_bytes"] = probes[si]->bytes();
        sj["work"] = probes[si]->work();
        j["surfaces"][probes[si]->surface()] = sj;
        auto med = [&](const char* k) {
            return sj[k].is_null() ? std::nan("") : sj[k]["median"].get<double>();
        };
        std::printf(
            "%s %s: holes %.3f%% (%.3f%% with the data's edges), false hits %.3f%% of %llu covered pixels; "
            "depth error median %.3f, surface distance median %.3f spacings; normal error median %.2f deg; "
            "%.2f Mrays/s\n",
            o.pool.c_str(), probes[si]->surface().c_str(), 100.0 * sj["hole_rate"].get<double>(),
            100.0 * sj["hole_rate_with_edges"].get<double>(), 100.0 * sj["false_hit_rate"].get<double>(),
            static_cast<unsigned long long>(totals[si].covered), med("depth_error_spacings"),
            med("surface_distance_spacings"), med("normal_error_degrees"),
            sj["rays_per_s"].get<double>() * 1e-6);
    }
    j["per_view"] = per_view;
    if (!o.json.empty()) write_file_atomic(o.json, j.dump(2) + "\n");
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    return prt::tool::run(
        argc, argv, "prt-fidelity",
        "Fidelity of a pool's surfaces (splats, iso, mls) against a real reference (issue 15): from --views "
        "views of --width x --height pixels, the holes (the reference is hit where the scan has data and the "
        "surface is missed), false hits (the surface hit more than --tolerance local spacings from the "
        "reference), depth and normal errors, in units of the local point spacing. The reference mesh is ray "
        "cast by an independent BVH in double. --images writes each view shaded and classified (grey good, "
        "red "
        "holes, blue false hits, dark green reference without data).",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("pool", o.pool, "Pool with the surfaces' sections")
                ->required()
                ->check(CLI::ExistingFile);
            app.add_option(
                   "--reference", o.reference,
                   "Reference mesh (.ply with faces, .obj, .off, .stl), in the pool's world frame (default: "
                   "the analytic shape of a prt-synth pool's provenance, ray cast exactly)")
                ->check(CLI::ExistingFile);
            app.add_option("--views-from", o.views_from,
                           "orbit: --views views spread over a sphere around the reference, looking at it; "
                           "sensors: the six faces of a cube map (fov 90) at each point sensor of the pool")
                ->check(CLI::IsMember({"orbit", "sensors"}));
            app.add_option(
                   "--surface", o.surfaces,
                   "Surfaces to measure, comma separated: splats, iso, mls (default: every one the pool "
                   "holds)")
                ->delimiter(',')
                ->check(CLI::IsMember({"splats", "iso", "mls"}));
            app.add_option(
                   "--points", o.points,
                   "Pool whose points say where the scan has data and its spacing (default: the pool's "
                   "own points)")
                ->check(CLI::ExistingFile);
            app.add_option("--views", o.views, "Views, spread over the sphere around the reference")
                ->check(CLI::Range(1u, 256u));
            app.add_option("--width", o.width, "Image width")->check(CLI::Range(8u, 8192u));
            app.add_option("--height", o.height, "Image height")->check(CLI::Range(8u, 8192u));
            app.add_option("--fov", o.fov,
                           "Vertical field of view, degrees (the reference's bounding sphere fills it)")
                ->check(CLI::Range(1.0f, 120.0f));
            app.add_option("--coverage", o.coverage,
                           "A reference hit within this many local spacings of an input point has data")
                ->check(CLI::Range(0.1, 100.0));
            app.add_option("--tolerance", o.tolerance,
                           "A surface hit farther than this many local spacings from the reference is false; "
                           "one this far behind the reference hit is a hole")
                ->check(CLI::Range(0.1, 100.0));
            app.add_option("-j,--threads", o.threads, "Threads (0 = all hardware threads)");
            app.add_option("--json", o.json, "Write the figures as JSON to this file (default: none)");
            app.add_option("--images", o.images,
                           "Write each view's reference, surfaces and classification maps into this folder "
                           "(default: none)");
            prt::bench::add_surface_options(app, o.s);
        },
        [&](const prt::tool::CommonOptions& common) { fidelity(o, common); });
}
