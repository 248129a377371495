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

/// A --width x --height pinhole view from `eye` towards `target` along `dir` (pool coordinates; the
/// camera in those relative to `origin`), field of view `fov` degrees; the up hint is +z where
/// |dir.y| > `up_limit`, +y otherwise.
View pinhole_view(const Options& o, const D3& origin, const D3& eye, const D3& target, const D3& dir,
                  double up_limit, float fov) {
    auto local = [&](const D3& a) {
        return core::Vec3{float(a[0] - origin[0]), float(a[1] - origin[1]), float(a[2] - origin[2])};
    };
    View v;
    v.origin = origin;
    v.direction = dir;
    v.eye = eye;
    v.width = o.width;
    v.height = o.height;
    const core::Vec3 up = std::abs(dir[1]) > up_limit ? core::Vec3{0, 0, 1} : core::Vec3{0, 1, 0};
    v.camera = core::make_pinhole(local(eye), local(target), up, fov, o.width, o.height);
    return v;
}

View make_view(const Options& o, const D3& origin, const D3& lo, const D3& hi, const D3& dir) {
    const D3 centre = mul(add(lo, hi), 0.5);
    const double diag = length(sub(hi, lo));
    const double dist = 0.5 * diag / std::sin(0.5 * o.fov * M_PI / 180.0);
    const D3 eye = add(centre, mul(dir, dist));
    return pinhole_view(o, origin, eye, centre, dir, 0.95, o.fov);
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
            views.push_back(pinhole_view(o, origin, eye, add(eye, dir), dir, 0.5, 90.0f));
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

/// One measurement: the reference and input points, then per view a reference pass, and per
/// surface a timed trace pass and a classification pass; figures summed over views.
class Fidelity {
public:
    Fidelity(Options o, const tool::CommonOptions& common)
        : m_o(std::move(o)),
          m_common(common),
          m_pool(std::make_shared<const pool::PoolFile>(pool::PoolFile::open(m_o.pool))) {
        const pool::ModelInfo& mi = m_pool->model_info();
        m_origin = {mi.origin[0], mi.origin[1], mi.origin[2]};
        m_threads = resolve_threads(m_o.threads);
        m_npx = std::size_t(m_o.width) * m_o.height;
        open_surfaces();
        load_points();
        m_truth = make_reference();
        tool::note(m_common.quiet,
                   "prt-fidelity: %zu input points (median spacing %.4g), reference %s, %.2f s", m_pts.size(),
                   m_sorted_spacing[m_sorted_spacing.size() / 2], m_truth->describe().dump().c_str(),
                   tool::now_seconds() - m_start);
        if (m_o.views_from == "sensors") {
            m_views = sensor_views(m_o, *m_pool, m_origin);
        } else {
            for (const D3& d : view_directions(m_o.views))
                m_views.push_back(make_view(m_o, m_origin, m_truth->lo(), m_truth->hi(), d));
        }
        m_totals.resize(m_probes.size());
    }

    void run() {
        if (!m_o.images.empty()) std::filesystem::create_directories(m_o.images);
        tool::Progress progress("prt-fidelity: views", m_views.size(), m_common.quiet);
        for (std::uint32_t vi = 0; vi < m_views.size(); ++vi) {
            const std::vector<RefPixel> ref = reference_pass(m_views[vi]);
            std::uint64_t covered = 0;
            for (const RefPixel& r : ref) covered += r.cls == RefClass::covered;
            nlohmann::json vj = {{"direction", m_views[vi].direction},
                                 {"eye", m_views[vi].eye},
                                 {"covered_pixels", covered},
                                 {"surfaces", nlohmann::json::object()}};
            if (!m_o.images.empty()) write_reference_image(m_views[vi], vi, ref);
            for (std::size_t si = 0; si < m_probes.size(); ++si) {
                const double t0 = tool::now_seconds();
                const std::vector<SurfPixel> surf = surface_pass(m_views[vi], *m_probes[si]);
                const double secs = tool::now_seconds() - t0;
                std::vector<PixClass> cls(m_npx, PixClass::none);
                Tally t = classify(m_views[vi], ref, surf, cls);
                t.seconds = secs;
                t.rays = m_npx;
                vj["surfaces"][m_probes[si]->surface()] = t.json(false);
                m_totals[si].merge(t);
                if (!m_o.images.empty())
                    write_surface_images(m_views[vi], vi, m_probes[si]->surface(), ref, surf, cls);
            }
            m_per_view.push_back(vj);
            progress.update(vi + 1);
        }
        progress.finish();
        report();
    }

private:
    /// The surfaces asked for, or every one the pool holds.
    void open_surfaces() {
        if (m_o.surfaces.empty()) {
            if (m_pool->has(pool::SectionType::splats)) m_o.surfaces.push_back("splats");
            if (m_pool->has(pool::SectionType::iso_info)) m_o.surfaces.push_back("iso");
            if (m_pool->has(pool::SectionType::mls_info)) m_o.surfaces.push_back("mls");
            if (m_o.surfaces.empty())
                throw Error(m_o.pool + ": holds no surface (run prt-octree, prt-iso or prt-mls)");
        }
        for (const std::string& s : m_o.surfaces)
            m_probes.push_back(std::make_unique<bench::SurfaceProbe>(m_pool, s, m_o.s));
    }

    /// The input points: where the scan has data, and its local spacing.
    void load_points() {
        m_start = tool::now_seconds();
        std::unique_ptr<pool::PoolFile> other;
        if (!m_o.points.empty()) other = std::make_unique<pool::PoolFile>(pool::PoolFile::open(m_o.points));
        m_pts = pre::read_point_sections(other ? *other : *m_pool).positions;
        if (m_pts.size() < 16)
            throw Error((m_o.points.empty() ? m_o.pool : m_o.points) + ": fewer than 16 points");
        m_index = std::make_unique<bench::PointIndex>(m_pts);
        m_spacing = m_index->local_spacing(m_threads);
        m_sorted_spacing = m_spacing;
        std::sort(m_sorted_spacing.begin(), m_sorted_spacing.end());
    }

    std::unique_ptr<Reference> make_reference() const {
        if (!m_o.reference.empty()) return std::make_unique<MeshTruth>(m_o.reference);
        try {
            return std::make_unique<AnalyticTruth>(*m_pool);
        } catch (const Error&) {
            throw Error(m_o.pool +
                        ": no reference: give --reference MESH, or a pool made by prt-synth (its "
                        "provenance names the analytic shape)");
        }
    }

    core::Ray world_ray(const View& view, std::uint32_t x, std::uint32_t y, D3& wo, D3& wd) const {
        const core::Ray r = core::primary_ray(view.camera, x, y, view.width, view.height);
        wo = add(m_origin, D3{r.origin.x, r.origin.y, r.origin.z});
        wd = D3{r.dir.x, r.dir.y, r.dir.z};
        return r;
    }

    /// The reference's first hit per pixel and where the scan has data (see the header).
    std::vector<RefPixel> reference_pass(const View& view) {
        std::vector<RefPixel> ref(m_npx);
        parallel_chunks(m_o.height, 1, m_threads, [&](std::size_t y0, std::size_t y1, unsigned) {
            std::vector<std::uint32_t> idx;
            std::vector<double> angles;
            for (std::size_t y = y0; y < y1; ++y)
                for (std::uint32_t x = 0; x < m_o.width; ++x) {
                    D3 wo, wd;
                    world_ray(view, x, std::uint32_t(y), wo, wd);
                    RefPixel& r = ref[y * m_o.width + x];
                    bench::MeshHit h;
                    if (!m_truth->intersect(wo, wd, h)) continue;
                    r.t = h.t;
                    r.point = h.point;
                    r.normal = dot(h.normal, wd) < 0 ? h.normal : mul(h.normal, -1.0);
                    if (!h.front) {
                        r.cls = RefClass::back_face;
                        continue;
                    }
                    double d;
                    r.spacing = m_spacing[m_index->nearest(h.point, d)];
                    if (d > m_o.coverage * r.spacing)
                        r.cls = RefClass::uncovered;
                    else if (surrounded(*m_index, h.point, r.normal, m_o.coverage * r.spacing, idx, angles))
                        r.cls = RefClass::covered;
                    else
                        r.cls = RefClass::edge;
                }
        });
        for (const RefPixel& r : ref) {
            m_ref_pixels += r.cls != RefClass::background;
            m_ref_covered += r.cls == RefClass::covered;
            m_ref_edge += r.cls == RefClass::edge;
            m_ref_uncovered += r.cls == RefClass::uncovered;
            m_ref_back += r.cls == RefClass::back_face;
        }
        return ref;
    }

    /// The surface's hit per pixel, through the core (the timed part).
    std::vector<SurfPixel> surface_pass(const View& view, const bench::SurfaceProbe& probe) const {
        std::vector<SurfPixel> surf(m_npx);
        parallel_chunks(m_o.height, 1, m_threads, [&](std::size_t y0, std::size_t y1, unsigned) {
            for (std::size_t y = y0; y < y1; ++y)
                for (std::uint32_t x = 0; x < m_o.width; ++x) {
                    const core::Ray r =
                        core::primary_ray(view.camera, x, std::uint32_t(y), view.width, view.height);
                    bench::ProbeHit h;
                    SurfPixel& s = surf[y * m_o.width + x];
                    if (probe.trace(r, h)) s.hit = true, s.t = float(h.t), s.normal = h.normal;
                }
        });
        return surf;
    }

    /// One pixel's class (the header's definitions), its errors into `t`.
    PixClass classify_pixel(const RefPixel& r, const SurfPixel& s, const D3& wo, const D3& wd,
                            Tally& t) const {
        const bool is_covered = r.cls == RefClass::covered;
        t.covered += is_covered;
        t.edge += r.cls == RefClass::edge;
        if (!s.hit) {
            if (is_covered) return ++t.holes, PixClass::hole;
            if (r.cls == RefClass::edge) return ++t.edge_holes, PixClass::edge_hole;
            return PixClass::none;
        }
        ++t.hits;
        const D3 xw = add(wo, mul(wd, double(s.t)));
        double dn;
        const double sx = m_spacing[m_index->nearest(xw, dn)];
        // False hit: farther than F spacings from the reference surface. Near the reference hit,
        // that distance is bounded by |x - h| without a query.
        const bool near_ref = r.cls != RefClass::background && length(sub(xw, r.point)) <= m_o.tolerance * sx;
        if (!near_ref && m_truth->distance(xw) > m_o.tolerance * sx)
            return ++t.false_hits, PixClass::false_hit;
        const double cosr = std::abs(dot(r.normal, wd));
        const double behind = (double(s.t) - r.t) * cosr;
        if (!is_covered) {
            if (r.cls == RefClass::edge && behind > m_o.tolerance * r.spacing)
                return ++t.edge_holes, PixClass::edge_hole;
            return PixClass::none;
        }
        if (behind > m_o.tolerance * r.spacing) return ++t.holes, PixClass::hole;
        ++t.good;
        t.depth.push_back(float(std::abs(double(s.t) - r.t) / r.spacing));
        t.distance.push_back(float(std::abs(double(s.t) - r.t) * cosr / r.spacing));
        const D3 n{s.normal.x, s.normal.y, s.normal.z};
        const double c = std::clamp(dot(n, r.normal) / std::max(1e-30, length(n)), -1.0, 1.0);
        t.normal_deg.push_back(float(std::acos(c) * 180.0 / M_PI));
        return PixClass::good;
    }

    /// Every pixel's class, per row, then merged.
    Tally classify(const View& view, const std::vector<RefPixel>& ref, const std::vector<SurfPixel>& surf,
                   std::vector<PixClass>& cls) const {
        std::vector<Tally> rows(m_o.height);
        parallel_chunks(m_o.height, 1, m_threads, [&](std::size_t y0, std::size_t y1, unsigned) {
            for (std::size_t y = y0; y < y1; ++y)
                for (std::uint32_t x = 0; x < m_o.width; ++x) {
                    const std::size_t i = y * m_o.width + x;
                    D3 wo, wd;
                    world_ray(view, x, std::uint32_t(y), wo, wd);
                    cls[i] = classify_pixel(ref[i], surf[i], wo, wd, rows[y]);
                }
        });
        Tally all;
        for (const Tally& t : rows) all.merge(t);
        return all;
    }

    void write_reference_image(const View& view, std::uint32_t vi, const std::vector<RefPixel>& ref) const {
        std::vector<std::uint32_t> img(m_npx, pack(0, 0, 0));
        for (std::uint32_t y = 0; y < m_o.height; ++y)
            for (std::uint32_t x = 0; x < m_o.width; ++x) {
                const RefPixel& r = ref[std::size_t(y) * m_o.width + x];
                D3 wo, wd;
                world_ray(view, x, y, wo, wd);
                const double g = shade(r.normal, wd);
                std::uint32_t& px = img[std::size_t(y) * m_o.width + x];
                if (r.cls == RefClass::covered) px = pack(g, g, g);
                if (r.cls == RefClass::uncovered) px = pack(0.2 * g, 0.45 * g, 0.2 * g);
                if (r.cls == RefClass::back_face) px = pack(0.4 * g, 0.3 * g, 0.1 * g);
                if (r.cls == RefClass::edge) px = pack(0.9 * g, 0.6 * g, 0.2 * g);
            }
        write_rgba(std::filesystem::path(m_o.images) / ("reference_view" + std::to_string(vi) + ".png"),
                   m_o.width, m_o.height, img);
    }

    void write_surface_images(const View& view, std::uint32_t vi, const std::string& surface,
                              const std::vector<RefPixel>& ref, const std::vector<SurfPixel>& surf,
                              const std::vector<PixClass>& cls) const {
        std::vector<std::uint32_t> shaded(m_npx, pack(0, 0, 0)), map(m_npx, pack(0, 0, 0));
        for (std::uint32_t y = 0; y < m_o.height; ++y)
            for (std::uint32_t x = 0; x < m_o.width; ++x) {
                const std::size_t i = std::size_t(y) * m_o.width + x;
                D3 wo, wd;
                world_ray(view, x, y, wo, wd);
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
        const std::string stem = surface + "_view" + std::to_string(vi);
        write_rgba(std::filesystem::path(m_o.images) / (stem + ".png"), m_o.width, m_o.height, shaded);
        write_rgba(std::filesystem::path(m_o.images) / (stem + "_class.png"), m_o.width, m_o.height, map);
    }

    /// The data itself against the reference: how far the input points lie from it, in their own
    /// spacings (noise, misregistration, outliers the import kept).
    void input_offsets(nlohmann::json& j) const {
        std::vector<float> off(m_pts.size());
        parallel_chunks(m_pts.size(), 4096, m_threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t i = b; i < e; ++i)
                off[i] = float(m_truth->distance(m_pts[i]) / std::max(m_spacing[i], 1e-300));
        });
        std::uint64_t far = 0;
        for (float d : off) far += d > m_o.tolerance;
        j["input_offset_spacings"] = summary(off);
        j["input_points_beyond_tolerance"] = far;
    }

    void report() const {
        nlohmann::json j;
        j["pool"] = m_o.pool;
        j["points"] = m_o.points.empty() ? m_o.pool : m_o.points;
        j["reference"] = m_truth->describe();
        j["views"] = m_views.size();
        j["views_from"] = m_o.views_from;
        j["width"] = m_o.width;
        j["height"] = m_o.height;
        j["fov_degrees"] = m_o.fov;
        j["coverage_spacings"] = m_o.coverage;
        j["tolerance_spacings"] = m_o.tolerance;
        j["threads"] = m_threads;
        j["input_points"] = m_pts.size();
        input_offsets(j);
        const auto& ss = m_sorted_spacing;
        j["spacing"] = {
            {"median", ss[ss.size() / 2]}, {"p10", ss[ss.size() / 10]}, {"p90", ss[ss.size() * 9 / 10]}};
        j["reference_pixels"] = {{"covered", m_ref_covered},
                                 {"edge", m_ref_edge},
                                 {"uncovered", m_ref_uncovered},
                                 {"back_face", m_ref_back},
                                 {"total", m_ref_pixels}};
        for (std::size_t si = 0; si < m_probes.size(); ++si) {
            nlohmann::json sj = m_totals[si].json(true);
            sj["settings"] = m_probes[si]->settings();
            sj["surface_bytes"] = m_probes[si]->bytes();
            sj["work"] = m_probes[si]->work();
            j["surfaces"][m_probes[si]->surface()] = sj;
            auto med = [&](const char* k) {
                return sj[k].is_null() ? std::nan("") : sj[k]["median"].get<double>();
            };
            std::printf(
                "%s %s: holes %.3f%% (%.3f%% with the data's edges), false hits %.3f%% of %llu covered "
                "pixels; "
                "depth error median %.3f, surface distance median %.3f spacings; normal error median %.2f "
                "deg; "
                "%.2f Mrays/s\n",
                m_o.pool.c_str(), m_probes[si]->surface().c_str(), 100.0 * sj["hole_rate"].get<double>(),
                100.0 * sj["hole_rate_with_edges"].get<double>(), 100.0 * sj["false_hit_rate"].get<double>(),
                static_cast<unsigned long long>(m_totals[si].covered), med("depth_error_spacings"),
                med("surface_distance_spacings"), med("normal_error_degrees"),
                sj["rays_per_s"].get<double>() * 1e-6);
        }
        j["per_view"] = m_per_view;
        if (!m_o.json.empty()) write_file_atomic(m_o.json, j.dump(2) + "\n");
    }

    Options m_o;
    const tool::CommonOptions& m_common;
    std::shared_ptr<const pool::PoolFile> m_pool;
    D3 m_origin{};
    unsigned m_threads = 1;
    std::size_t m_npx = 0;
    double m_start = 0;
    std::vector<std::unique_ptr<bench::SurfaceProbe>> m_probes;
    std::vector<D3> m_pts;
    std::unique_ptr<bench::PointIndex> m_index;
    std::vector<double> m_spacing, m_sorted_spacing;
    std::unique_ptr<Reference> m_truth;
    std::vector<View> m_views;
    std::vector<Tally> m_totals;
    nlohmann::json m_per_view = nlohmann::json::array();
    std::uint64_t m_ref_covered = 0, m_ref_uncovered = 0, m_ref_back = 0, m_ref_pixels = 0, m_ref_edge = 0;
};

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
                ->check(prt::tool::ExistingInput);
            app.add_option(
                   "--reference", o.reference,
                   "Reference mesh (.ply with faces, .obj, .off, .stl), in the pool's world frame (default: "
                   "the analytic shape of a prt-synth pool's provenance, ray cast exactly)")
                ->check(prt::tool::ExistingInput);
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
                ->check(prt::tool::ExistingInput);
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
            app.add_option("-j,--threads", o.threads, "Threads (0 = every core the process may use)");
            app.add_option("--json", o.json, "Write the figures as JSON to this file (default: none)");
            app.add_option("--images", o.images,
                           "Write each view's reference, surfaces and classification maps into this folder "
                           "(default: none)");
            prt::bench::add_surface_options(app, o.s);
        },
        [&](const prt::tool::CommonOptions& common) {
            if (!o.json.empty()) prt::check_writable(o.json);  // before the (long) measurement
            Fidelity(o, common).run();
        });
}
