// patch-bench: CPU benchmark of the patch core (seed 002, 5.4: one ray per task, early
// termination) on primary rays: rays per second for 1..N threads, median of several frames after a
// warm-up, and per-ray work (BVH nodes, subpatch boxes, Newton runs and iterations). Optionally
// writes the image (normals as colours) as PPM. Output: a table on stdout, --json FILE for JSON.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "patch_build.h"
#include "patch_file.h"
#include "patch_pool.h"
#include "prt/core/patch.h"
#include "prt/formats/pool.h"
#include "prt/runtime/surface_pools.h"
#include "prt/tool.h"

namespace {

using prt::core::DVec3;

struct Camera {
    DVec3 eye, forward, right, up;
    double tan_half;
};

/// Looks at the model's box centre from direction (azimuth, elevation) in degrees, z up, the box's
/// bounding sphere filling `fill` of the vertical field of view (40 degrees).
Camera make_camera(const prt::pool::PatchInfo& info, double azimuth, double elevation, double fill) {
    const double k = 3.14159265358979323846 / 180.0;
    DVec3 lo{info.bounds_min[0], info.bounds_min[1], info.bounds_min[2]};
    DVec3 hi{info.bounds_max[0], info.bounds_max[1], info.bounds_max[2]};
    const DVec3 centre = (lo + hi) * 0.5;
    const double radius = 0.5 * prt::core::length(hi - lo);
    Camera c;
    c.tan_half = std::tan(20.0 * k);
    const double dist = radius / (fill * std::sin(20.0 * k));
    const DVec3 dir{std::cos(elevation * k) * std::cos(azimuth * k),
                    std::cos(elevation * k) * std::sin(azimuth * k), std::sin(elevation * k)};
    c.eye = centre + dir * dist;
    c.forward = -dir;
    c.right = prt::core::cross(c.forward, DVec3{0, 0, 1});
    c.right = c.right * (1.0 / prt::core::length(c.right));
    c.up = prt::core::cross(c.right, c.forward);
    return c;
}

struct Totals {
    std::uint64_t rays = 0, hits = 0;
    std::uint64_t bvh_nodes = 0, patches = 0, subpatch_boxes = 0, newton_runs = 0, newton_iterations = 0;
    std::uint64_t hit_iterations = 0;
    void add(const Totals& o) {
        rays += o.rays, hits += o.hits, bvh_nodes += o.bvh_nodes, patches += o.patches;
        subpatch_boxes += o.subpatch_boxes, newton_runs += o.newton_runs,
            newton_iterations += o.newton_iterations;
        hit_iterations += o.hit_iterations;
    }
};

struct Frame {
    std::vector<float> rgb;  // optional image
    Totals totals;
    double seconds = 0;
};

Frame render(const prt::core::PatchView& view, const Camera& cam, int size, unsigned threads,
             const prt::core::PatchTraceParams& params, const prt::core::PatchCullMask* cull, bool image) {
    Frame f;
    if (image) f.rgb.assign(std::size_t(size) * size * 3, 0.0f);
    std::atomic<int> next_row{0};
    std::vector<Totals> per(threads);
    const double t0 = prt::tool::now_seconds();
    auto work = [&](unsigned id) {
        Totals& t = per[id];
        for (int y; (y = next_row.fetch_add(1)) < size;) {
            for (int x = 0; x < size; ++x) {
                const double sx = ((x + 0.5) / size * 2.0 - 1.0) * cam.tan_half;
                const double sy = (1.0 - (y + 0.5) / size * 2.0) * cam.tan_half;
                const DVec3 d = cam.forward + cam.right * sx + cam.up * sy;
                const prt::core::PatchRay ray{cam.eye, d, 1e30, 0};
                prt::core::PatchHit hit;
                prt::core::PatchStats st;
                const bool h = prt::core::trace_patches(view, ray, params, hit, &st, cull);
                ++t.rays;
                t.bvh_nodes += st.bvh_nodes, t.patches += st.patches, t.subpatch_boxes += st.subpatch_boxes;
                t.newton_runs += st.newton_runs, t.newton_iterations += st.newton_iterations;
                if (h) {
                    ++t.hits;
                    t.hit_iterations += hit.iterations;
                    if (image) {
                        DVec3 n = hit.front ? hit.normal : -hit.normal;  // two-sided
                        float* px = &f.rgb[(std::size_t(y) * size + x) * 3];
                        px[0] = float(0.5 + 0.5 * n.x), px[1] = float(0.5 + 0.5 * n.y),
                        px[2] = float(0.5 + 0.5 * n.z);
                    }
                }
            }
        }
    };
    std::vector<std::thread> pool;
    for (unsigned i = 1; i < threads; ++i) pool.emplace_back(work, i);
    work(0);
    for (auto& th : pool) th.join();
    f.seconds = prt::tool::now_seconds() - t0;
    for (const auto& t : per) f.totals.add(t);
    return f;
}

}  // namespace

int main(int argc, char** argv) {
    std::string input = std::string(PRT_SHARED_DATA_DIR) + "/bezier/teapot";
    int size = 512;
    unsigned max_threads = 2;
    int frames = 5;
    std::uint32_t depth = 6;
    double azimuth = -60, elevation = 25, fill = 1.5;
    bool cull = false;
    bool faces_by_ray = false;
    std::string image_path, json_path;

    return prt::tool::run(
        argc, argv, "patch-bench", "CPU benchmark of Bezier patch ray tracing (primary rays, seed 002 5.4)",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("input", input, "Patch file (.bpt / Newell) or a pool made by prt-patches");
            app.add_option("--size", size, "Image width and height in pixels")->check(CLI::Range(1, 8192));
            app.add_option("--threads", max_threads, "Measure 1, 2, ... up to this many threads")
                ->check(CLI::Range(1u, 256u));
            app.add_option("--frames", frames,
                           "Timed frames per thread count (median reported), after one warm-up")
                ->check(CLI::Range(1, 1000));
            app.add_option("--depth", depth, "Subpatch tree depth when building from a patch file")
                ->check(CLI::Range(0u, prt::pool::k_max_subpatch_depth));
            app.add_option("--azimuth", azimuth, "Camera azimuth in degrees (about z)");
            app.add_option("--elevation", elevation, "Camera elevation in degrees");
            app.add_option("--fill", fill, "Fraction of the vertical field the bounding sphere fills")
                ->check(CLI::Range(0.01, 10.0));
            app.add_flag("--cull", cull, "Back-face culling per view (oriented pools only)");
            app.add_flag("--front-only", faces_by_ray, "Keep front faces only (k_patch_faces_by_ray)");
            app.add_option("--image", image_path, "Write the last frame's normals as a binary PPM");
            app.add_option("--json", json_path, "Write the results as JSON");
        },
        [&](const prt::tool::CommonOptions& common) {
            std::vector<std::byte> bytes;
            if (std::filesystem::path(input).extension() == ".pool") {
                std::ifstream in(input, std::ios::binary);
                if (!in) throw prt::Error(input + ": cannot open");
                const std::string text{std::istreambuf_iterator<char>(in), {}};
                bytes.resize(text.size());
                std::memcpy(bytes.data(), text.data(), text.size());
            } else {
                auto set = prt::patches::read_patch_file(input, prt::patches::PatchFormat::automatic);
                prt::patches::BuildOptions o;
                o.depth = depth;
                auto model = prt::patches::build_patch_model(std::move(set.nets), o);
                prt::pool::PoolWriter w;
                prt::patches::write_patch_sections(model, w);
                bytes = w.serialize();
            }
            const auto pool = prt::pool::PoolFile::from_bytes(std::move(bytes), input);
            const prt::core::PatchView view = prt::rt::load_patch_view(pool);
            const auto& info = pool.array<prt::pool::PatchInfo>(prt::pool::SectionType::patch_info)[0];
            const Camera cam = make_camera(info, azimuth, elevation, fill);
            prt::core::PatchTraceParams params;
            if (faces_by_ray) params.faces = prt::core::k_patch_faces_by_ray;
            std::vector<std::uint32_t> node_words, bvh_words;
            prt::core::PatchCullMask mask;
            double mark_seconds = 0;
            if (cull) {
                if (!(view.flags & prt::pool::k_patch_oriented))
                    throw prt::Error(input +
                                     ": not oriented: back-face culling needs prt-patches --orient outward");
                node_words.resize(std::size_t(view.patch_count) * prt::core::patch_cull_words(view));
                bvh_words.resize(prt::core::bvh_cull_words(view));
                const double t0 = prt::tool::now_seconds();
                for (std::uint32_t p = 0; p < view.patch_count; ++p)
                    prt::core::mark_backfacing_patch(view, p, cam.eye, node_words.data());
                prt::core::mark_backfacing_bvh(view, node_words.data(), bvh_words.data());
                mark_seconds = prt::tool::now_seconds() - t0;
                mask = {node_words.data(), bvh_words.data()};
            }
            nlohmann::json out = {{"input", input},
                                  {"size", size},
                                  {"patches", view.patch_count},
                                  {"depth", view.subpatch_depth},
                                  {"cull", cull},
                                  {"front_only", faces_by_ray},
                                  {"cull_mark_seconds", mark_seconds},
                                  {"hardware_threads", std::thread::hardware_concurrency()},
                                  {"runs", nlohmann::json::array()}};
            std::printf("%-8s %12s %10s %8s %9s %9s %9s %9s %9s\n", "threads", "rays/s", "ms/frame", "hit %",
                        "bvh/ray", "patch/ray", "sub/ray", "newton/r", "iter/ray");
            Frame last;
            for (unsigned threads = 1; threads <= max_threads; ++threads) {
                render(view, cam, size, threads, params, cull ? &mask : nullptr, false);  // warm-up
                std::vector<double> times;
                Frame f;
                for (int i = 0; i < frames; ++i) {
                    f = render(view, cam, size, threads, params, cull ? &mask : nullptr,
                               !image_path.empty() && threads == max_threads && i == frames - 1);
                    times.push_back(f.seconds);
                }
                std::sort(times.begin(), times.end());
                const double median = times[times.size() / 2];
                const Totals& t = f.totals;
                const double r = double(t.rays);
                const double rays_per_s = r / median;
                std::printf("%-8u %12.0f %10.2f %8.2f %9.2f %9.2f %9.2f %9.2f %9.2f\n", threads, rays_per_s,
                            median * 1e3, 100.0 * t.hits / r, t.bvh_nodes / r, t.patches / r,
                            t.subpatch_boxes / r, t.newton_runs / r, t.newton_iterations / r);
                out["runs"].push_back({{"threads", threads},
                                       {"median_seconds", median},
                                       {"min_seconds", times.front()},
                                       {"max_seconds", times.back()},
                                       {"rays_per_second", rays_per_s},
                                       {"rays", t.rays},
                                       {"hits", t.hits},
                                       {"per_ray",
                                        {{"bvh_nodes", t.bvh_nodes / r},
                                         {"patches", t.patches / r},
                                         {"subpatch_boxes", t.subpatch_boxes / r},
                                         {"newton_runs", t.newton_runs / r},
                                         {"newton_iterations", t.newton_iterations / r}}},
                                       {"per_hit",
                                        {{"newton_iterations_of_the_root",
                                          t.hits ? double(t.hit_iterations) / t.hits : 0.0}}}});
                if (!f.rgb.empty()) last = std::move(f);
            }
            if (!image_path.empty() && !last.rgb.empty()) {
                std::ofstream img(image_path, std::ios::binary);
                img << "P6\n" << size << " " << size << "\n255\n";
                for (float c : last.rgb)
                    img.put(static_cast<char>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f)));
                if (!img) throw prt::Error(image_path + ": cannot write");
            }
            if (!json_path.empty()) {
                std::ofstream js(json_path);
                js << out.dump(2) << "\n";
                if (!js) throw prt::Error(json_path + ": cannot write");
            }
            prt::tool::note(common.quiet, "patch-bench: %u patches, depth %u%s", view.patch_count,
                            view.subpatch_depth, cull ? ", back-face culling" : "");
        });
}
