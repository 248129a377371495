// mls-bench: CPU benchmark of the MLS surface (WS05 4.1-4.3): primary rays of a pinhole camera at
// WxH through every pixel, traced with the core's trace_mls from 1..N threads; reports rays/s
// (median of --repeat runs after one warm-up), the per-ray statistics of WS05 4.3 (kd traversal
// steps, cells, surface intersections, splats), and accuracy: against the reference settings
// (mls_trace.h reference_params, double sums) and, for prt-synth pools, against the analytic shape.
// Not a test: scripts/bench-mls.sh runs it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "analytic.h"
#include "cpu_seconds.h"
#include "mls_pool.h"
#include "mls_trace.h"
#include "prt/formats/pool.h"
#include "prt/runtime/surface_pools.h"
#include "prt/tool.h"

namespace {

using prt::core::Vec3;

using prt::test::cpu_seconds;

std::vector<unsigned> parse_list(const std::string& s) {
    std::vector<unsigned> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) out.push_back(static_cast<unsigned>(std::stoul(item)));
    return out;
}

/// Primary rays of a pinhole camera looking at `target` from `eye` (local frame), y up.
std::vector<prt::core::Ray> camera_rays(Vec3 eye, Vec3 target, float fov_degrees, unsigned w, unsigned h) {
    using namespace prt::core;
    const Vec3 fwd = normalize(target - eye);
    Vec3 right = normalize(cross(fwd, Vec3{0, 1, 0}));
    if (!(length2(right) > 0.5f)) right = Vec3{1, 0, 0};
    const Vec3 up = cross(right, fwd);
    const float tan_half = std::tan(fov_degrees * 0.5f * k_pi / 180.0f);
    const float aspect = float(w) / float(h);
    std::vector<Ray> rays;
    rays.reserve(std::size_t(w) * h);
    for (unsigned y = 0; y < h; ++y)  // row by row: neighbouring rays in one work chunk
        for (unsigned x = 0; x < w; ++x) {
            const float u = ((float(x) + 0.5f) / float(w) * 2.0f - 1.0f) * tan_half * aspect;
            const float v = (1.0f - (float(y) + 0.5f) / float(h) * 2.0f) * tan_half;
            rays.push_back(Ray{eye, normalize(fwd + right * u + up * v), k_inf, 0u});
        }
    return rays;
}

}  // namespace

int main(int argc, char** argv) {
    std::string input, json_path, image_path, threads_list = "1,2";
    unsigned width = 512, height = 512, repeat = 3;
    prt::core::MlsParams params;
    float zoom = 1.0f;
    bool no_reference = false;
    std::vector<float> view_dir = {0.25f, 0.3f, 1.0f};

    return prt::tool::run(
        argc, argv, "mls-bench",
        "Benchmark MLS primary rays on the CPU (WS05 4.1-4.3): rays/s, per-ray statistics, accuracy.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("input", input, "Pool with MLS sections (prt-mls)")->required();
            app.add_option("--width", width, "Image width")->capture_default_str();
            app.add_option("--height", height, "Image height")->capture_default_str();
            app.add_option("--threads", threads_list, "Comma-separated thread counts")->capture_default_str();
            app.add_option("--repeat", repeat, "Timed runs per thread count (median)")->capture_default_str();
            app.add_option("--samples", params.samples, "Samples per cell interval (k)")
                ->capture_default_str();
            app.add_option("--refine", params.refine_steps, "Regula falsi steps")->capture_default_str();
            app.add_option("--zoom", zoom, "Camera distance divisor (1 = whole model in view)")
                ->capture_default_str();
            app.add_option("--dir", view_dir, "Direction from the model centre to the eye")->expected(3);
            app.add_flag("--no-reference", no_reference, "Skip the accuracy comparison");
            app.add_option("--json", json_path, "Write the results as JSON here");
            app.add_option("--image", image_path, "Write the bench hits as a binary PPM (headlight shading)");
        },
        [&](const prt::tool::CommonOptions& common) {
            using namespace prt;
            const pool::PoolFile pool = pool::PoolFile::open(input);
            const core::MlsView view = rt::load_mls_view(pool);
            const pool::ModelInfo& mi = pool.model_info();
            Vec3 lo{mi.bounds_min[0], mi.bounds_min[1], mi.bounds_min[2]};
            Vec3 hi{mi.bounds_max[0], mi.bounds_max[1], mi.bounds_max[2]};
            const Vec3 centre = (lo + hi) * 0.5f;
            const float radius = core::length(hi - lo) * 0.5f;
            const float fov = 40.0f;
            const float dist = radius / std::sin(fov * 0.5f * core::k_pi / 180.0f) / zoom;
            const Vec3 eye = centre + core::normalize(Vec3{view_dir[0], view_dir[1], view_dir[2]}) * dist;
            const std::vector<core::Ray> rays = camera_rays(eye, centre, fov, width, height);

            nlohmann::json out = {{"input", input},
                                  {"width", width},
                                  {"height", height},
                                  {"samples", params.samples},
                                  {"refine", params.refine_steps},
                                  {"zoom", zoom},
                                  {"nodes", view.node_count},
                                  {"refs", view.ref_count},
                                  {"splats", view.splat_count},
                                  {"depth", view.depth}};
            mls::TraceResult last;
            nlohmann::json runs = nlohmann::json::array();
            for (const unsigned t : parse_list(threads_list)) {
                mls::trace_rays(view, rays, params, t);  // warm-up
                std::vector<double> rates, cpu_rates;
                for (unsigned r = 0; r < std::max(1u, repeat); ++r) {
                    const double c0 = cpu_seconds();
                    last = mls::trace_rays(view, rays, params, t);
                    const double cpu = cpu_seconds() - c0;
                    rates.push_back(last.totals.rays_per_second());
                    cpu_rates.push_back(cpu > 0 ? double(rays.size()) / cpu : 0.0);
                }
                std::sort(rates.begin(), rates.end());
                std::sort(cpu_rates.begin(), cpu_rates.end());
                const double median = rates[rates.size() / 2];
                const double cpu_median = cpu_rates[cpu_rates.size() / 2];
                runs.push_back({{"threads", t},
                                {"rays_per_second", median},
                                {"min", rates.front()},
                                {"max", rates.back()},
                                {"rays_per_cpu_second", cpu_median}});
                tool::note(common.quiet,
                           "mls-bench: %u thread(s): %.0f rays/s (median of %zu; %.0f..%.0f), %.0f rays per "
                           "CPU second",
                           t, median, rates.size(), rates.front(), rates.back(), cpu_median);
            }
            const mls::TraceTotals& tt = last.totals;
            out["runs"] = runs;
            out["hit_fraction"] = double(tt.hits) / double(tt.rays);
            out["per_ray"] = {
                {"traversal_steps", tt.per_ray(tt.traversal_steps)}, {"cells", tt.per_ray(tt.cells)},
                {"intersections", tt.per_ray(tt.intersections)},     {"splats", tt.per_ray(tt.splats)},
                {"evaluations", tt.per_ray(tt.evaluations)},         {"truncated", tt.truncated}};
            tool::note(
                common.quiet,
                "mls-bench: per ray: %.2f traversal steps, %.2f cells, %.3f intersections, %.2f splats, "
                "%.2f evaluations of F; hits %.1f%%",
                tt.per_ray(tt.traversal_steps), tt.per_ray(tt.cells), tt.per_ray(tt.intersections),
                tt.per_ray(tt.splats), tt.per_ray(tt.evaluations), 100.0 * double(tt.hits) / double(tt.rays));

            if (!no_reference) {
                // The same settings with double sums: what float accumulation costs in accuracy.
                const mls::TraceResult dbl = mls::trace_rays(view, rays, params, 0, mls::Precision::dual);
                std::uint64_t flips = 0, n_both = 0;
                double fd_max = 0.0, fd_sum = 0.0;
                for (std::size_t i = 0; i < rays.size(); ++i) {
                    if ((dbl.found[i] != 0) != (last.found[i] != 0)) {
                        ++flips;
                    } else if (dbl.found[i]) {
                        const double dt = std::abs(double(dbl.hits[i].t) - double(last.hits[i].t)) / radius;
                        fd_max = std::max(fd_max, dt);
                        fd_sum += dt;
                        ++n_both;
                    }
                }
                out["float_vs_double"] = {{"flips", flips},
                                          {"mean_dt_over_size", n_both ? fd_sum / double(n_both) : 0.0},
                                          {"max_dt_over_size", fd_max}};
                tool::note(
                    common.quiet,
                    "mls-bench: float vs double sums (same settings): %llu hit/miss flips, |dt| mean %.2e, "
                    "max %.2e of the model radius",
                    (unsigned long long)flips, n_both ? fd_sum / double(n_both) : 0.0, fd_max);
                const mls::TraceResult ref =
                    mls::trace_rays(view, rays, mls::reference_params(), 0, mls::k_reference_precision);
                std::uint64_t both = 0, only_ref = 0, only_fast = 0;
                double sum_dt = 0.0, max_dt = 0.0, sum_dn = 0.0;
                for (std::size_t i = 0; i < rays.size(); ++i) {
                    if (ref.found[i] && last.found[i]) {
                        ++both;
                        const double dt = std::abs(double(ref.hits[i].t) - double(last.hits[i].t)) / radius;
                        sum_dt += dt;
                        max_dt = std::max(max_dt, dt);
                        sum_dn += std::acos(std::clamp(
                            double(core::dot(ref.hits[i].normal, last.hits[i].normal)), -1.0, 1.0));
                    } else if (ref.found[i]) {
                        ++only_ref;
                    } else if (last.found[i]) {
                        ++only_fast;
                    }
                }
                out["vs_reference"] = {
                    {"both", both},
                    {"missed", only_ref},
                    {"extra", only_fast},
                    {"mean_dt_over_size", both ? sum_dt / double(both) : 0.0},
                    {"max_dt_over_size", max_dt},
                    {"mean_normal_deg", both ? sum_dn / double(both) * 180.0 / M_PI : 0.0}};
                tool::note(
                    common.quiet,
                    "mls-bench: vs reference (16 samples, 12 refinements, double): %llu both, %llu missed, "
                    "%llu extra; |dt| mean %.2e, max %.2e of the model radius; normals %.3f deg",
                    (unsigned long long)both, (unsigned long long)only_ref, (unsigned long long)only_fast,
                    both ? sum_dt / double(both) : 0.0, max_dt,
                    both ? sum_dn / double(both) * 180.0 / M_PI : 0.0);
                // Synthetic pools: distance of the hits from the analytic surface.
                bool synthetic = (mi.flags & pool::k_model_synthetic) != 0;
                if (synthetic) {
                    const synth::Shape shape = synth::shape_from_provenance(pool.provenance_json(), input);
                    const double size = synth::shape_size(shape);
                    for (int pass = 0; pass < 2; ++pass) {
                        const mls::TraceResult& res = pass == 0 ? last : ref;
                        double sum = 0.0, worst = 0.0, sum_n = 0.0;
                        std::uint64_t n = 0;
                        for (std::size_t i = 0; i < rays.size(); ++i) {
                            if (!res.found[i]) continue;
                            const Vec3 p = res.hits[i].position;
                            const synth::Vec3 w{p.x + mi.origin[0], p.y + mi.origin[1], p.z + mi.origin[2]};
                            const synth::SurfacePoint sp = synth::closest(shape, w);
                            const double e = std::abs(sp.signed_distance) / size;
                            sum += e;
                            worst = std::max(worst, e);
                            const Vec3 nn = res.hits[i].normal;
                            const double c = nn.x * sp.normal[0] + nn.y * sp.normal[1] + nn.z * sp.normal[2];
                            sum_n += std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI;
                            ++n;
                        }
                        const char* which = pass == 0 ? "bench" : "reference";
                        out[std::string("vs_analytic_") + which] = {
                            {"hits", n},
                            {"mean_over_size", n ? sum / double(n) : 0.0},
                            {"max_over_size", worst},
                            {"mean_normal_deg", n ? sum_n / double(n) : 0.0}};
                        tool::note(
                            common.quiet,
                            "mls-bench: %s hits vs the analytic %s: distance mean %.2e, max %.2e of its size "
                            "(%.4g); normals %.3f deg",
                            which, synth::shape_name(shape.kind), n ? sum / double(n) : 0.0, worst, size,
                            n ? sum_n / double(n) : 0.0);
                    }
                }
            }
            if (!image_path.empty()) {
                std::ofstream f(image_path, std::ios::binary);
                f << "P6\n" << width << " " << height << "\n255\n";
                for (std::size_t i = 0; i < rays.size(); ++i) {
                    unsigned char c[3] = {40, 40, 60};
                    if (last.found[i]) {
                        const float l = std::abs(core::dot(last.hits[i].normal, rays[i].dir));
                        const auto g =
                            static_cast<unsigned char>(std::clamp(30.0f + 220.0f * l, 0.0f, 255.0f));
                        c[0] = c[1] = c[2] = g;
                    }
                    f.write(reinterpret_cast<const char*>(c), 3);
                }
                if (!f) throw Error(image_path + ": cannot write");
            }
            if (!json_path.empty()) {
                std::ofstream f(json_path);
                f << out.dump(2) << "\n";
                if (!f) throw Error(json_path + ": cannot write");
            }
        });
}
