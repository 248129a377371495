// prt-accuracy: the speed/accuracy figures of one surface of one pool (issue 9), measured on the
// CPU through the core's own per-ray functions (the ones the renderer and the CUDA kernels call):
//
//   splats   closest_hit_splats (thesis 3.3 blending, 3.5 deep blending, 3.4 leaf bounds)
//   iso      trace_iso (thesis 4.5: sampling, interpolation, Illinois refinement; q8 or f32 leaves)
//   mls      trace_mls<float|double> (Wald-Seidel 2005, 3.2: k samples per cell interval)
//   patches  trace_patches (seed 002, 3: Newton in double; iteration cap and tolerance)
//
// A pinhole camera's primary rays (one per pixel) are traced; the program reports rays per second
// (median of --repeat timed runs after one warm-up, all threads), and, where a ground truth
// exists, the hit-point error and the hole rate:
//
//   prt-synth pools: the analytic shape named in the pool's provenance (prt::synth). The true hit
//     of each ray is synth::first_hit's: exact ray casting against the shape in double. Hit error =
//     distance of the representation's hit point from the true surface; depth error = |t - t_true|
//     where both hit; both relative to the model's bounding-box diagonal (mean, p99, max).
//   patch pools: an independent reference: every patch tessellated into a fine grid of triangles
//     (Bernstein basis evaluated in long double, not the core's evaluator), the nearest triangle
//     hit refined by a 3x3 Newton solve Q(u,v) = o + t d in long double. Hit error = |p - p_ref|.
//   other pools (real scans): rays/s and the hit fraction only; image error comes from `compare`.
//
//   hole rate  = pixels whose ray hits the true surface but not the representation / true hits
//   false hits = pixels the representation hits where the true surface is missed / true misses
//
// Every surface is shaded the same way (a grey headlight Lambert on the surface's own normal), so
// `prt-accuracy compare A B` (RMSE, PSNR of two such images, e.g. against the MLS reference at
// k = 16 in double) measures what a viewer sees: silhouettes, holes and normals.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analytic.h"
#include "prt/atomic_file.h"
#include "prt/core/camera.h"
#include "prt/core/iso.h"
#include "prt/core/mls.h"
#include "prt/core/patch.h"
#include "prt/core/splat.h"
#include "prt/formats/pool.h"
#include "prt/parallel.h"
#include "prt/runtime/image.h"
#include "prt/runtime/render_scene.h"
#include "prt/runtime/surface_pools.h"
#include "prt/tool.h"
#include "prt/vec3.h"
#include "ray_reference.h"
#include "surface_probe.h"

namespace {

using namespace prt;
using core::Vec3;
using D3 = Vec3d;
using L3 = std::array<long double, 3>;

struct Options {
    std::string pool, surface = "splats", json, image;
    std::uint32_t width = 256, height = 256, threads = 0, repeat = 3;
    float fov = 40.0f;
    std::vector<double> view{0.55, 0.45, 0.7};
    bench::SurfaceSettings s = both_faces();
    std::uint32_t reference_grid = 64;  // patches
    /// prt-accuracy measures the MLS surface with both faces (its figures since issue 9).
    static bench::SurfaceSettings both_faces() {
        bench::SurfaceSettings s;
        s.mls_both_faces = true;
        return s;
    }
};

/// What one primary ray found.
struct PixelResult {
    bool hit = false;
    double t = 0;
    D3 position{};  ///< world frame
    Vec3 normal{0, 0, 1};
};

/// The camera in the pool's local frame plus the local frame's world origin; world rays are
/// origin + (o + t d) with o, d exactly the float values the core traces.
struct View {
    core::PinholeCamera camera;
    D3 origin{};
    std::uint32_t width = 0, height = 0;
    core::Ray ray(std::uint32_t x, std::uint32_t y) const {
        return core::primary_ray(camera, x, y, width, height);
    }
};

View make_view(const Options& o, const D3& origin, const D3& lo, const D3& hi) {
    const D3 centre = mul(add(lo, hi), 0.5);
    const double diag = length(sub(hi, lo));
    D3 dir{o.view[0], o.view[1], o.view[2]};
    const double len = length(dir);
    if (!(len > 0) || !std::isfinite(len)) throw Error("--view: must be a finite non-zero vector");
    dir = mul(dir, 1.0 / len);
    // Distance at which the bounding sphere just fills the vertical field of view.
    const double dist = 0.5 * diag / std::sin(0.5 * o.fov * M_PI / 180.0);
    const D3 eye = add(centre, mul(dir, dist));
    View v;
    v.origin = origin;
    v.width = o.width;
    v.height = o.height;
    auto f = [](const D3& a) { return Vec3{float(a[0]), float(a[1]), float(a[2])}; };
    const Vec3 up = std::abs(dir[1]) > 0.99 ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
    v.camera = core::make_pinhole(f(eye), f(centre), up, o.fov, o.width, o.height);
    return v;
}

// ---- Ground truth: analytic shapes --------------------------------------------------------------

/// Entry and exit t of the ray o + t d with the box [lo, hi] (slabs in double).
bool box_interval(const D3& o, const D3& d, const D3& lo, const D3& hi, double& t0, double& t1) {
    t0 = 0;
    t1 = std::numeric_limits<double>::infinity();
    return bench::clip_to_box(o, d, lo, hi, t0, t1);
}

// ---- Ground truth: patches (independent tessellation + long double Newton) -------------------

/// Cubic Bernstein basis and its derivative at t, long double.
void bernstein(long double t, long double b[4], long double db[4]) {
    const long double s = 1 - t;
    b[0] = s * s * s, b[1] = 3 * t * s * s, b[2] = 3 * t * t * s, b[3] = t * t * t;
    db[0] = -3 * s * s, db[1] = 3 * s * s - 6 * t * s, db[2] = 6 * t * s - 3 * t * t, db[3] = 3 * t * t;
}

/// Q(u, v), dQ/du, dQ/dv of a control net (formats/patch_layout.h: p[4 i + j], i along u).
void eval_net(const pool::PatchControlNet& net, long double u, long double v, L3& q, L3& qu, L3& qv) {
    long double bu[4], dbu[4], bv[4], dbv[4];
    bernstein(u, bu, dbu);
    bernstein(v, bv, dbv);
    q = qu = qv = L3{0, 0, 0};
    for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
            const pool::PatchPoint& p = net.p[4 * i + j];
            const long double c[3] = {p.x, p.y, p.z};
            for (int a = 0; a < 3; ++a) {
                q[a] += bu[i] * bv[j] * c[a];
                qu[a] += dbu[i] * bv[j] * c[a];
                qv[a] += bu[i] * dbv[j] * c[a];
            }
        }
    }
}

struct Box3 {
    D3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
    D3 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity()};
    void grow(const D3& p) {
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    }
};

/// Every patch as an n x n grid of (u, v) samples, grouped in blocks of 8 x 8 cells with boxes.
class TessellatedPatches {
public:
    TessellatedPatches(const core::PatchView& view, std::uint32_t n)
        : m_view(view), m_n(std::max(8u, n / 8 * 8)) {
        const std::uint32_t g = m_n + 1;
        m_points.resize(std::size_t(view.patch_count) * g * g);
        m_blocks = m_n / 8;
        m_block_boxes.resize(std::size_t(view.patch_count) * m_blocks * m_blocks);
        m_patch_boxes.resize(view.patch_count);
        for (std::uint32_t p = 0; p < view.patch_count; ++p) {
            for (std::uint32_t i = 0; i <= m_n; ++i) {
                for (std::uint32_t j = 0; j <= m_n; ++j) {
                    L3 q, qu, qv;
                    eval_net(view.nets[p], (long double)i / m_n, (long double)j / m_n, q, qu, qv);
                    point(p, i, j) = D3{double(q[0]), double(q[1]), double(q[2])};
                }
            }
            for (std::uint32_t bi = 0; bi < m_blocks; ++bi) {
                for (std::uint32_t bj = 0; bj < m_blocks; ++bj) {
                    Box3& b = m_block_boxes[(std::size_t(p) * m_blocks + bi) * m_blocks + bj];
                    for (std::uint32_t i = bi * 8; i <= bi * 8 + 8; ++i)
                        for (std::uint32_t j = bj * 8; j <= bj * 8 + 8; ++j) b.grow(point(p, i, j));
                    m_patch_boxes[p].grow(b.lo);
                    m_patch_boxes[p].grow(b.hi);
                }
            }
        }
    }

    /// Nearest hit of the ray (o + t d, local frame, double) with the tessellation, refined onto the
    /// patch by Newton in long double. Returns false on a miss.
    bool trace(const D3& o, const D3& d, PixelResult& out) const {
        double best = std::numeric_limits<double>::infinity();
        std::uint32_t best_patch = 0;
        double best_u = 0, best_v = 0;
        const double pad = 1e-9 * m_view.extent;
        auto box_hit = [&](const Box3& b) {
            double t0, t1;
            return box_interval(o, d, sub(b.lo, D3{pad, pad, pad}), add(b.hi, D3{pad, pad, pad}), t0, t1) &&
                   t0 < best;
        };
        for (std::uint32_t p = 0; p < m_view.patch_count; ++p) {
            if (!box_hit(m_patch_boxes[p])) continue;
            for (std::uint32_t bi = 0; bi < m_blocks; ++bi) {
                for (std::uint32_t bj = 0; bj < m_blocks; ++bj) {
                    if (!box_hit(m_block_boxes[(std::size_t(p) * m_blocks + bi) * m_blocks + bj])) continue;
                    for (std::uint32_t i = bi * 8; i < bi * 8 + 8; ++i) {
                        for (std::uint32_t j = bj * 8; j < bj * 8 + 8; ++j) {
                            const D3 &a = point(p, i, j), &b = point(p, i + 1, j), &c = point(p, i, j + 1),
                                     &e = point(p, i + 1, j + 1);
                            double t, s1, s2;
                            // two triangles per cell: (a, b, c) and (e, c, b)
                            if (triangle(o, d, a, b, c, t, s1, s2) && t < best) {
                                best = t, best_patch = p;
                                best_u = (i + s1) / m_n, best_v = (j + s2) / m_n;
                            }
                            if (triangle(o, d, e, c, b, t, s1, s2) && t < best) {
                                best = t, best_patch = p;
                                best_u = (i + 1 - s1) / m_n, best_v = (j + 1 - s2) / m_n;
                            }
                        }
                    }
                }
            }
        }
        if (!std::isfinite(best)) return false;
        refine(best_patch, o, d, best, best_u, best_v, out);
        return true;
    }

private:
    D3& point(std::uint32_t p, std::uint32_t i, std::uint32_t j) {
        return m_points[(std::size_t(p) * (m_n + 1) + i) * (m_n + 1) + j];
    }
    const D3& point(std::uint32_t p, std::uint32_t i, std::uint32_t j) const {
        return m_points[(std::size_t(p) * (m_n + 1) + i) * (m_n + 1) + j];
    }

    /// Moller-Trumbore, two-sided; s1, s2 the barycentrics of b and c.
    static bool triangle(const D3& o, const D3& d, const D3& a, const D3& b, const D3& c, double& t,
                         double& s1, double& s2) {
        const D3 e1 = sub(b, a), e2 = sub(c, a);
        const D3 p{d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
        const double det = dot(e1, p);
        if (det == 0 || !std::isfinite(det)) return false;
        const double inv = 1.0 / det;
        const D3 s = sub(o, a);
        s1 = dot(s, p) * inv;
        if (s1 < 0 || s1 > 1) return false;
        const D3 q{s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
        s2 = dot(d, q) * inv;
        if (s2 < 0 || s1 + s2 > 1) return false;
        t = dot(e2, q) * inv;
        return t > 0;
    }

    /// Newton on F(u, v, t) = Q(u, v) - o - t d = 0 (long double; Cramer's rule on [Qu Qv -d]).
    /// Keeps the tessellation's hit when the solve leaves the patch or does not converge.
    void refine(std::uint32_t p, const D3& o, const D3& d, double t_tess, double u0, double v0,
                PixelResult& out) const {
        long double u = u0, v = v0, t = t_tess;
        bool ok = false;
        L3 q, qu, qv;
        for (int it = 0; it < 40; ++it) {
            eval_net(m_view.nets[p], u, v, q, qu, qv);
            const L3 f{q[0] - o[0] - t * d[0], q[1] - o[1] - t * d[1], q[2] - o[2] - t * d[2]};
            const long double res = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
            // converged: a few ulps of the coordinates (models far from the origin) or of the extent
            const long double mag = std::abs(q[0]) + std::abs(q[1]) + std::abs(q[2]);
            if (res <= 1e-14L * (m_view.extent + mag)) {
                ok = true;
                break;
            }
            const L3 c3{-(long double)d[0], -(long double)d[1], -(long double)d[2]};
            auto det3 = [](const L3& a, const L3& b, const L3& c) {
                return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                       a[2] * (b[0] * c[1] - b[1] * c[0]);
            };
            // columns qu, qv, c3; solve J x = f
            auto col_det = [&](const L3& c0, const L3& c1, const L3& c2) {
                return det3(L3{c0[0], c1[0], c2[0]}, L3{c0[1], c1[1], c2[1]}, L3{c0[2], c1[2], c2[2]});
            };
            const long double det = col_det(qu, qv, c3);
            if (det == 0 || !std::isfinite((double)det)) break;
            u -= col_det(f, qv, c3) / det;
            v -= col_det(qu, f, c3) / det;
            t -= col_det(qu, qv, f) / det;
            if (u < -0.01L || u > 1.01L || v < -0.01L || v > 1.01L) break;
        }
        if (!ok) {  // the tessellation's own hit (counted by the caller through `refined`)
            u = u0, v = v0, t = t_tess;
            eval_net(m_view.nets[p], u, v, q, qu, qv);
            q = L3{o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        }
        out.hit = true;
        out.t = double(t);
        out.position = D3{double(q[0]), double(q[1]), double(q[2])};
        const long double n[3] = {qu[1] * qv[2] - qu[2] * qv[1], qu[2] * qv[0] - qu[0] * qv[2],
                                  qu[0] * qv[1] - qu[1] * qv[0]};
        const long double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        out.normal = l > 0 ? Vec3{float(n[0] / l), float(n[1] / l), float(n[2] / l)} : Vec3{0, 0, 1};
        if (!ok) ++m_unrefined;
    }

    const core::PatchView& m_view;
    std::uint32_t m_n, m_blocks;
    std::vector<D3> m_points;
    std::vector<Box3> m_block_boxes, m_patch_boxes;

public:
    mutable std::atomic<std::uint64_t> m_unrefined{0};  ///< reference hits Newton could not refine
};

// ---- Statistics ------------------------------------------------------------------------------

nlohmann::json summary(std::vector<double> v, double diag) {
    if (v.empty()) return nullptr;
    std::sort(v.begin(), v.end());
    double sum = 0;
    for (double x : v) sum += x;
    const std::size_t p99 = std::min(v.size() - 1, std::size_t(std::ceil(0.99 * double(v.size()))) - 1);
    return {{"mean", sum / double(v.size()) / diag},
            {"p99", v[p99] / diag},
            {"max", v.back() / diag},
            {"count", v.size()}};
}

/// Grey headlight Lambert on the surface's own normal (two-sided), linear; background black.
rt::Image shade(const std::vector<PixelResult>& px, const View& view) {
    rt::Image img;
    img.resize(view.width, view.height);
    for (std::uint32_t y = 0; y < view.height; ++y) {
        for (std::uint32_t x = 0; x < view.width; ++x) {
            const std::size_t i = std::size_t(y) * view.width + x;
            float c = 0;
            if (px[i].hit) c = 0.1f + 0.9f * std::abs(core::dot(px[i].normal, view.ray(x, y).dir));
            if (!std::isfinite(c)) c = 0;
            for (int k = 0; k < 3; ++k) img.rgb[3 * i + k] = c;
            const auto b = std::uint32_t(std::lround(std::pow(std::clamp(c, 0.0f, 1.0f), 1 / 2.2f) * 255));
            img.rgba8[i] = b | (b << 8) | (b << 16) | (0xffu << 24);
        }
    }
    return img;
}

// ---- Tracing one surface ------------------------------------------------------------------------

/// Runs `trace(ray, result)` over every pixel on `threads` threads; returns the wall seconds.
template <class Trace>
double trace_image(const View& view, unsigned threads, std::vector<PixelResult>& px, Trace&& trace) {
    px.assign(std::size_t(view.width) * view.height, PixelResult{});
    const double t0 = tool::now_seconds();
    parallel_chunks(view.height, 1, threads, [&](std::size_t y0, std::size_t y1, unsigned) {
        for (std::size_t y = y0; y < y1; ++y)
            for (std::uint32_t x = 0; x < view.width; ++x)
                trace(view.ray(x, std::uint32_t(y)), px[y * view.width + x]);
    });
    return tool::now_seconds() - t0;
}

/// Local-frame hit (float t along the float ray) to a world PixelResult.
void set_hit(PixelResult& r, const View& view, const core::Ray& ray, double t, Vec3 normal) {
    r.hit = true;
    r.t = t;
    const D3 o{ray.origin.x, ray.origin.y, ray.origin.z}, d{ray.dir.x, ray.dir.y, ray.dir.z};
    r.position = add(view.origin, add(o, mul(d, t)));
    r.normal = normal;
}

struct Measured {
    std::vector<PixelResult> px;
    std::vector<double> seconds;
    nlohmann::json settings, work;
    std::uint64_t bytes = 0;  ///< bytes of the sections this surface reads
};

/// The surface's image (warm-up) and --repeat timed runs, through the core's per-ray functions.
void run_surface(const Options& o, const View& view, Measured& m,
                 std::shared_ptr<const pool::PoolFile> shared) {
    const bench::SurfaceProbe probe(std::move(shared), o.surface, o.s);
    m.bytes = probe.bytes();
    m.settings = probe.settings();
    const unsigned threads = resolve_threads(o.threads);
    auto trace = [&](const core::Ray& r, PixelResult& out) {
        bench::ProbeHit h;
        if (!probe.trace(r, h)) return;
        if (h.has_position) {  // patches: the hit evaluated in double at the root
            out.hit = true;
            out.t = h.t;
            out.position = add(view.origin, h.position);
            out.normal = h.normal;
        } else {
            set_hit(out, view, r, h.t, h.normal);
        }
    };
    trace_image(view, threads, m.px, trace);  // warm-up (and the image)
    for (std::uint32_t r = 0; r < o.repeat; ++r) {
        std::vector<PixelResult> tmp;
        m.seconds.push_back(trace_image(view, threads, tmp, trace));
    }
    m.work = probe.work();
}

void accuracy(const Options& o, const tool::CommonOptions& common) {
    // Outputs that cannot be written are refused before the measurement runs.
    if (!o.json.empty()) check_writable(o.json);
    if (!o.image.empty()) check_writable(o.image);
    auto shared = std::make_shared<const pool::PoolFile>(pool::PoolFile::open(o.pool));
    const pool::PoolFile& p = *shared;
    const pool::ModelInfo& mi = p.model_info();
    const D3 origin{mi.origin[0], mi.origin[1], mi.origin[2]};
    D3 lo{mi.bounds_min[0], mi.bounds_min[1], mi.bounds_min[2]},
        hi{mi.bounds_max[0], mi.bounds_max[1], mi.bounds_max[2]};
    std::unique_ptr<core::PatchView> patch_view;
    if (o.surface == "patches") {
        patch_view = std::make_unique<core::PatchView>(rt::load_patch_view(p));
        Box3 b;
        for (std::uint32_t i = 0; i < patch_view->patch_count; ++i)
            for (const pool::PatchPoint& q : patch_view->nets[i].p) b.grow(D3{q.x, q.y, q.z});
        lo = b.lo, hi = b.hi;
    }
    if (!(length(sub(hi, lo)) > 0) || !std::isfinite(length(sub(hi, lo))))
        throw Error(o.pool + ": empty or non-finite model bounds");
    const View view = make_view(o, origin, lo, hi);

    // Ground truth.
    std::string truth = "none";
    synth::Shape shape;
    double diag = length(sub(hi, lo));
    std::vector<PixelResult> ref;
    std::unique_ptr<TessellatedPatches> tess;
    if (o.surface == "patches") {
        truth = "tessellation + long double Newton";
        tess = std::make_unique<TessellatedPatches>(*patch_view, o.reference_grid);
    } else {
        try {
            shape = synth::shape_from_provenance(p.provenance_json(), o.pool);
            truth = "analytic";
            const auto b = synth::shape_bounds(shape);
            diag = length(sub(b[1], b[0]));
        } catch (const Error&) {
        }
    }
    if (truth != "none") {
        tool::note(common.quiet, "prt-accuracy: ground truth (%s) for %ux%u rays\n", truth.c_str(), o.width,
                   o.height);
        trace_image(view, resolve_threads(o.threads), ref, [&](const core::Ray& r, PixelResult& out) {
            const D3 d{r.dir.x, r.dir.y, r.dir.z};
            const D3 ol{r.origin.x, r.origin.y, r.origin.z};
            if (tess) {
                if (tess->trace(ol, d, out)) out.position = add(view.origin, out.position);
                return;
            }
            // world-frame ray (d is unit: primary_ray normalizes)
            const D3 ow = add(view.origin, ol);
            if (const auto h = synth::first_hit(shape, ow, d)) {
                out.hit = true;
                out.t = h->t;
                out.position = add(ow, mul(d, h->t));
            }
        });
    }

    tool::note(common.quiet, "prt-accuracy: %s, %ux%u rays, 1 warm-up + %u timed runs\n", o.surface.c_str(),
               o.width, o.height, o.repeat);
    Measured m;
    run_surface(o, view, m, shared);

    // Figures.
    std::vector<double> hit_err, depth_err, normal_deg;
    std::uint64_t hits = 0, true_hits = 0, holes = 0, false_hits = 0, nan = 0;
    for (std::size_t i = 0; i < m.px.size(); ++i) {
        const PixelResult& r = m.px[i];
        if (r.hit) ++hits;
        if (r.hit &&
            (!std::isfinite(r.t) || !std::isfinite(length(r.position)) || !core::is_finite(r.normal)))
            ++nan;
        if (truth == "none") continue;
        if (ref[i].hit) ++true_hits;
        if (ref[i].hit && !r.hit) ++holes;
        if (!ref[i].hit && r.hit) ++false_hits;
        if (!r.hit) continue;
        if (truth == "analytic") {
            const synth::SurfacePoint sp = synth::closest(shape, r.position);
            hit_err.push_back(std::abs(sp.signed_distance));
            const double c =
                std::abs(r.normal.x * sp.normal[0] + r.normal.y * sp.normal[1] + r.normal.z * sp.normal[2]);
            normal_deg.push_back(std::acos(std::min(1.0, c)) * 180.0 / M_PI);
        }
        if (ref[i].hit) {
            depth_err.push_back(std::abs(r.t - ref[i].t));
            if (truth != "analytic") hit_err.push_back(length(sub(r.position, ref[i].position)));
        }
    }
    std::vector<double> s = m.seconds;
    std::sort(s.begin(), s.end());
    const double med = s[s.size() / 2];
    const double rays = double(o.width) * o.height;
    std::uint64_t points = mi.point_count;

    nlohmann::json j;
    j["pool"] = o.pool;
    j["surface"] = o.surface;
    j["settings"] = m.settings;
    j["width"] = o.width;
    j["height"] = o.height;
    j["threads"] = resolve_threads(o.threads);
    j["truth"] = truth;
    j["diagonal"] = diag;
    j["points"] = points;
    j["surface_bytes"] = m.bytes;
    j["bytes_per_point"] = points > 0 ? nlohmann::json(double(m.bytes) / double(points)) : nlohmann::json();
    j["seconds"] = m.seconds;
    j["rays_per_s"] = rays / med;
    j["rays_per_s_best"] = rays / s.front();  // the least disturbed run (shared machines)
    j["hit_fraction"] = double(hits) / rays;
    j["nan_hits"] = nan;
    j["work"] = m.work;
    if (truth != "none") {
        j["true_hit_fraction"] = double(true_hits) / rays;
        j["hole_rate"] = true_hits ? double(holes) / double(true_hits) : 0.0;
        j["false_hit_rate"] =
            rays - double(true_hits) > 0 ? double(false_hits) / (rays - double(true_hits)) : 0.0;
        j["hit_error"] = summary(hit_err, diag);
        j["depth_error"] = summary(depth_err, diag);
        if (!normal_deg.empty()) {
            double sum = 0;
            for (double a : normal_deg) sum += a;
            j["normal_error_degrees_mean"] = sum / double(normal_deg.size());
        }
        if (tess) j["reference_unrefined"] = tess->m_unrefined.load();
    }
    std::printf("%s %s %s: %.3f Mrays/s, hits %.2f%%", o.pool.c_str(), o.surface.c_str(),
                m.settings.dump().c_str(), rays / med / 1e6, 100.0 * double(hits) / rays);
    if (truth != "none" && !hit_err.empty())
        std::printf(", hit error mean %.3e p99 %.3e max %.3e (of the diagonal), holes %.4f%%",
                    j["hit_error"]["mean"].get<double>(), j["hit_error"]["p99"].get<double>(),
                    j["hit_error"]["max"].get<double>(), 100.0 * j["hole_rate"].get<double>());
    std::printf("\n");
    if (nan) throw Error(o.pool + ": " + std::to_string(nan) + " hits with non-finite values");
    if (!o.image.empty()) rt::write_image(o.image, shade(m.px, view));
    if (!o.json.empty()) write_file_atomic(o.json, j.dump(2) + "\n");
}

// ---- compare: RMSE / PSNR of two images ----------------------------------------------------------

/// Display-encoded [0,1] values of an image file: 8-bit formats as stored, float formats (PFM,
/// EXR) after the same encoding shade() applies (clamp, gamma 1/2.2), so both kinds compare alike.
std::vector<float> display_values(const std::string& path, std::uint32_t& w, std::uint32_t& h) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    std::vector<float> v;
    if (ext == ".ppm") {
        const rt::Image img = rt::read_ppm(path);
        w = img.width, h = img.height;
        for (std::uint32_t c : img.rgba8)
            for (int k = 0; k < 3; ++k) v.push_back(float((c >> (8 * k)) & 0xffu) / 255.0f);
        return v;
    }
    const rt::FloatImage img = rt::read_float_image(path);  // PFM; anything OIIO reads when built with it
    w = img.width, h = img.height;
    for (float x : img.rgb) {
        if (!std::isfinite(x)) throw Error(path + ": non-finite pixel value");
        v.push_back(std::pow(std::clamp(x, 0.0f, 1.0f), 1 / 2.2f));
    }
    return v;
}

void compare(const std::string& a, const std::string& b, const std::string& json) {
    if (!json.empty()) check_writable(json);
    std::uint32_t wa, ha, wb, hb;
    const std::vector<float> va = display_values(a, wa, ha), vb = display_values(b, wb, hb);
    if (wa != wb || ha != hb)
        throw Error(b + ": size " + std::to_string(wb) + "x" + std::to_string(hb) + " differs from " + a +
                    "'s " + std::to_string(wa) + "x" + std::to_string(ha));
    double se = 0, max_abs = 0;
    for (std::size_t i = 0; i < va.size(); ++i) {
        const double d = double(va[i]) - double(vb[i]);
        se += d * d;
        max_abs = std::max(max_abs, std::abs(d));
    }
    const double rmse = std::sqrt(se / double(va.size()));
    const double psnr = rmse > 0 ? 20.0 * std::log10(1.0 / rmse) : std::numeric_limits<double>::infinity();
    std::printf("%s vs %s: RMSE %.6f, PSNR %.2f dB, max |diff| %.4f\n", a.c_str(), b.c_str(), rmse, psnr,
                max_abs);
    if (!json.empty()) {
        const nlohmann::json j = {
            {"a", a},
            {"b", b},
            {"rmse", rmse},
            {"psnr_db", std::isfinite(psnr) ? nlohmann::json(psnr) : nlohmann::json("inf")},
            {"max_abs", max_abs},
            {"peak", 1.0},
            {"encoding", "display (gamma 2.2), [0,1]"}};
        write_file_atomic(json, j.dump(2) + "\n");
    }
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    std::string cmp_a, cmp_b, cmp_json;
    CLI::App* cmp = nullptr;
    return prt::tool::run(
        argc, argv, "prt-accuracy",
        "Speed and accuracy of one surface (splats, iso, mls, patches) of one pool on the CPU: rays/s, "
        "hit-point "
        "error and hole rate against the analytic shape of a prt-synth pool (or a tessellated reference for "
        "patches), and a shaded image. `prt-accuracy compare A B` gives the RMSE and PSNR of two images.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("pool", o.pool, "Pool with the sections of --surface")
                ->check(prt::tool::ExistingInput);
            app.add_option("--surface", o.surface, "splats, iso, mls or patches")
                ->check(CLI::IsMember({"splats", "iso", "mls", "patches"}));
            app.add_option("--width", o.width, "Image width")->check(CLI::Range(1u, 8192u));
            app.add_option("--height", o.height, "Image height")->check(CLI::Range(1u, 8192u));
            app.add_option("--fov", o.fov, "Vertical field of view, degrees")
                ->check(CLI::Range(1.0f, 120.0f));
            app.add_option("--view", o.view, "Direction from the model's centre to the eye")->expected(3);
            app.add_option("-j,--threads", o.threads, "Threads (0 = every core the process may use)");
            app.add_option("--repeat", o.repeat, "Timed runs after one warm-up; the median is reported")
                ->check(CLI::Range(1u, 1000u));
            app.add_option("--json", o.json, "Write the figures as JSON to this file (default: none)");
            app.add_option(
                "--image", o.image,
                "Write the shaded image (.ppm/.pfm always; .png/.exr with OpenImageIO) (default: none)");
            bench::add_surface_options(app, o.s);
            app.add_option("--reference-grid", o.reference_grid,
                           "patches: reference tessellation, grid cells per patch edge")
                ->check(CLI::Range(8u, 1024u));
            cmp = app.add_subcommand("compare",
                                     "RMSE and PSNR (peak 1, display encoding) of image B against A");
            cmp->add_option("a", cmp_a, "Reference image (.ppm, .pfm; more with OpenImageIO)")
                ->required()
                ->check(prt::tool::ExistingInput);
            cmp->add_option("b", cmp_b, "Image to measure, same size")
                ->required()
                ->check(prt::tool::ExistingInput);
            cmp->add_option("--json", cmp_json, "Write the figures as JSON to this file (default: none)");
            app.final_callback([&] {
                if (!cmp->parsed() && o.pool.empty())
                    throw CLI::RequiredError("a pool (or the compare subcommand)");
            });
        },
        [&](const prt::tool::CommonOptions& common) {
            if (cmp->parsed())
                compare(cmp_a, cmp_b, cmp_json);
            else
                accuracy(o, common);
        });
}
