// iso-bench: CPU benchmark of the ISO core (prt/core/iso.h): primary rays of a pinhole camera at
// W x H through every pixel of a pool's ISO, traced with trace_iso from --threads threads, for the
// quantized and the float leaves when present. Reports rays/s (median of --repeat runs after one
// warm-up; CPU seconds too, steadier on a shared machine), per-ray work (leaves visited, filled
// leaves searched, trilinear evaluations), and, for prt-synth pools, the accuracy against the
// analytic shape (distance of the hit from the surface, normal angle). Not a test:
// scripts/bench-iso.sh runs it.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "analytic.h"
#include "cpu_seconds.h"
#include "iso_pool.h"
#include "prt/formats/pool.h"
#include "prt/parallel.h"
#include "prt/runtime/surface_pools.h"
#include "prt/tool.h"

namespace {

using prt::core::Vec3;

using prt::test::cpu_seconds;

struct Frame {
    std::vector<prt::core::IsoHit> hits;
    std::vector<std::uint8_t> found;
    std::uint64_t leaves = 0, filled = 0, evaluations = 0, truncated = 0, fixes = 0;
    double wall = 0, cpu = 0;
};

Frame render(const prt::core::IsoView& v, const prt::core::IsoParams& params, Vec3 eye, Vec3 target,
             float fov, unsigned w, unsigned h, unsigned threads) {
    using namespace prt::core;
    const Vec3 fwd = normalize(target - eye);
    Vec3 right = normalize(cross(fwd, Vec3{0, 1, 0}));
    const Vec3 up = cross(right, fwd);
    const float tan_half = std::tan(fov * 0.5f * k_pi / 180.0f);
    Frame f;
    f.hits.resize(std::size_t(w) * h);
    f.found.resize(std::size_t(w) * h);
    std::atomic<unsigned> next_row{0};
    std::atomic<std::uint64_t> leaves{0}, filled{0}, evaluations{0}, truncated{0}, fixes{0};
    const double c0 = cpu_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    auto work = [&] {
        std::uint64_t l = 0, fl = 0, e = 0, tr = 0, fx = 0;
        for (unsigned y; (y = next_row.fetch_add(1)) < h;) {
            for (unsigned x = 0; x < w; ++x) {
                const float u = ((float(x) + 0.5f) / float(w) * 2.0f - 1.0f) * tan_half * float(w) / float(h);
                const float vv = (1.0f - (float(y) + 0.5f) / float(h) * 2.0f) * tan_half;
                const Vec3 d = normalize(fwd + right * u + up * vv);
                IsoStats st;
                const std::size_t i = std::size_t(y) * w + x;
                f.found[i] = trace_iso(v, eye, d, k_inf, false, params, f.hits[i], st) ? 1 : 0;
                l += st.leaves, fl += st.filled, e += st.evaluations, tr += st.truncated,
                    fx += st.normal_fixes;
            }
        }
        leaves += l, filled += fl, evaluations += e, truncated += tr, fixes += fx;
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
    f.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    f.cpu = cpu_seconds() - c0;
    f.leaves = leaves, f.filled = filled, f.evaluations = evaluations, f.truncated = truncated,
    f.fixes = fixes;
    return f;
}

}  // namespace

int main(int argc, char** argv) {
    std::string input, json_path, image_path, storage = "all";
    unsigned width = 512, height = 512, threads = 0, repeat = 5, refine = 2;
    float samples = 4.0f, seam = 0.05f;
    return prt::tool::run(
        argc, argv, "iso-bench",
        "CPU benchmark of the ISO core: primary rays through every pixel, rays/s, per-ray work, accuracy "
        "against the analytic shape for prt-synth pools.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("input", input, "Pool with ISO sections (prt-iso)")->required();
            app.add_option("--width", width, "Image width")->check(CLI::Range(1u, 16384u));
            app.add_option("--height", height, "Image height")->check(CLI::Range(1u, 16384u));
            app.add_option("-j,--threads", threads, "Threads (0 = every core the process may use)");
            app.add_option("--repeat", repeat, "Timed runs (median reported) after one warm-up")
                ->check(CLI::Range(1u, 1000u));
            app.add_option("--storage", storage, "q8, f32 or all (every leaf array present)")
                ->check(CLI::IsMember({"q8", "f32", "all"}));
            app.add_option("--samples", samples, "IsoParams::samples");
            app.add_option("--refine", refine, "IsoParams::refine_steps");
            app.add_option("--seam", seam, "IsoParams::seam_extension");
            app.add_option("--json", json_path, "Write the results as JSON");
            app.add_option(
                "--image", image_path,
                "Write the first run of each leaf array as a binary PPM (headlight Lambert x color); "
                "the leaf kind is inserted before the extension");
        },
        [&](const prt::tool::CommonOptions& common) {
            using namespace prt;
            if (threads == 0) threads = prt::available_cores();
            const pool::PoolFile p = pool::PoolFile::open(input);
            const pool::IsoInfo& info = p.array<pool::IsoInfo>(pool::SectionType::iso_info).empty()
                                            ? throw Error(input + ": no ISO (run prt-iso)")
                                            : p.array<pool::IsoInfo>(pool::SectionType::iso_info)[0];
            bool synthetic = false;
            synth::Shape shape;
            try {
                shape = synth::shape_from_provenance(p.provenance_json(), input);
                synthetic = true;
            } catch (const Error&) {
            }
            const pool::ModelInfo& mi = p.model_info();
            const Vec3 lo{mi.bounds_min[0], mi.bounds_min[1], mi.bounds_min[2]};
            const Vec3 hi{mi.bounds_max[0], mi.bounds_max[1], mi.bounds_max[2]};
            const Vec3 centre = (lo + hi) * 0.5f;
            const float extent = core::max3(hi - lo);
            const Vec3 eye = centre + core::normalize(Vec3{0.55f, 0.45f, 0.7f}) * (1.9f * extent);
            core::IsoParams params;
            params.samples = samples;
            params.refine_steps = refine;
            params.seam_extension = seam;
            nlohmann::json results = nlohmann::json::array();
            std::printf("# %s: %u leaves, %u nodes, depth %u; %ux%u primary rays, %u threads, median of %u\n",
                        input.c_str(), info.leaf_count, info.node_count, info.depth, width, height, threads,
                        repeat);
            std::printf("%-5s %10s %10s %9s %9s %9s %7s %12s %12s\n", "leaf", "Mrays/s", "Mrays/cpu-s",
                        "leaves", "filled", "evals", "hit%", "max|d|", "mean|angle|");
            for (const bool q8 : {true, false}) {
                if ((q8 && !(info.flags & pool::k_iso_has_q8)) ||
                    (!q8 && !(info.flags & pool::k_iso_has_f32)))
                    continue;
                if ((storage == "q8" && !q8) || (storage == "f32" && q8)) continue;
                const core::IsoView v = rt::load_iso_view(p, q8);
                render(v, params, eye, centre, 40.0f, width, height, threads);  // warm-up
                std::vector<Frame> frames;
                for (unsigned r = 0; r < repeat; ++r)
                    frames.push_back(render(v, params, eye, centre, 40.0f, width, height, threads));
                std::vector<double> walls, cpus;
                for (const Frame& f : frames) walls.push_back(f.wall), cpus.push_back(f.cpu);
                std::sort(walls.begin(), walls.end());
                std::sort(cpus.begin(), cpus.end());
                const double rays = double(width) * height;
                const Frame& f = frames.front();
                std::uint64_t hits = 0;
                double max_d = 0, sum_angle = 0;
                for (std::size_t i = 0; i < f.hits.size(); ++i) {
                    if (!f.found[i]) continue;
                    ++hits;
                    if (!synthetic) continue;
                    const core::IsoHit& h = f.hits[i];
                    const synth::Vec3 wp{h.position.x + mi.origin[0], h.position.y + mi.origin[1],
                                         h.position.z + mi.origin[2]};
                    const synth::SurfacePoint sp = synth::closest(shape, wp);
                    max_d = std::max(max_d, std::abs(sp.signed_distance));
                    const double c =
                        h.normal.x * sp.normal[0] + h.normal.y * sp.normal[1] + h.normal.z * sp.normal[2];
                    sum_angle += std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI;
                }
                if (!image_path.empty()) {
                    std::string path = image_path;
                    const std::size_t dot = path.rfind('.');
                    path.insert(dot == std::string::npos ? path.size() : dot, q8 ? "_q8" : "_f32");
                    std::ofstream img(path, std::ios::binary);
                    img << "P6\n" << width << " " << height << "\n255\n";
                    const Vec3 fwd = prt::core::normalize(centre - eye);
                    for (std::size_t i = 0; i < f.hits.size(); ++i) {
                        unsigned char rgb[3] = {30, 30, 40};
                        if (f.found[i]) {
                            const float shade =
                                0.15f + 0.85f * std::abs(prt::core::dot(f.hits[i].normal, fwd));
                            const Vec3 c = f.hits[i].color * (255.0f * shade);
                            rgb[0] = static_cast<unsigned char>(std::clamp(c.x, 0.0f, 255.0f));
                            rgb[1] = static_cast<unsigned char>(std::clamp(c.y, 0.0f, 255.0f));
                            rgb[2] = static_cast<unsigned char>(std::clamp(c.z, 0.0f, 255.0f));
                        }
                        img.write(reinterpret_cast<const char*>(rgb), 3);
                    }
                    if (!img) throw Error(path + ": cannot write the image");
                }
                const double mrays = rays / walls[walls.size() / 2] / 1e6,
                             mrays_cpu = rays / cpus[cpus.size() / 2] / 1e6;
                std::printf("%-5s %10.3f %10.3f %9.2f %9.2f %9.2f %7.1f %12.3e %12.3f\n", q8 ? "q8" : "f32",
                            mrays, mrays_cpu, double(f.leaves) / rays, double(f.filled) / rays,
                            double(f.evaluations) / rays, 100.0 * double(hits) / rays,
                            synthetic ? max_d : NAN, synthetic && hits ? sum_angle / double(hits) : NAN);
                results.push_back(
                    {{"leaf", q8 ? "q8" : "f32"},
                     {"mrays_per_s", mrays},
                     {"mrays_per_cpu_s", mrays_cpu},
                     {"leaves_per_ray", double(f.leaves) / rays},
                     {"filled_per_ray", double(f.filled) / rays},
                     {"evaluations_per_ray", double(f.evaluations) / rays},
                     {"hit_fraction", double(hits) / rays},
                     {"truncated", f.truncated},
                     {"normal_fixes", f.fixes},
                     {"max_distance", synthetic ? nlohmann::json(max_d) : nlohmann::json()},
                     {"mean_normal_degrees",
                      synthetic && hits ? nlohmann::json(sum_angle / double(hits)) : nlohmann::json()}});
            }
            if (!json_path.empty()) {
                const nlohmann::json j = {
                    {"pool", input},      {"width", width},   {"height", height}, {"threads", threads},
                    {"samples", samples}, {"refine", refine}, {"seam", seam},     {"leaves", info.leaf_count},
                    {"results", results}};
                std::ofstream out(json_path);
                out << j.dump(2) << "\n";
                if (!out) throw Error(json_path + ": cannot write");
            }
            (void)common;
        });
}
