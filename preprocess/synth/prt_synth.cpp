// prt-synth: analytic point sets with exact ground truth, written as pools (issue 2, synthetic models).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "point_cloud.h"
#include "prt/pool_step.h"
#include "scan.h"
#include "synth.h"

namespace {

/// "X,Y,Z" as three finite numbers; throws prt::Error naming the option.
prt::synth::Vec3 parse_vec3(const std::string& option, const std::string& text) {
    prt::synth::Vec3 v{};
    const char* p = text.c_str();
    for (int a = 0; a < 3; ++a) {
        char* end = nullptr;
        v[a] = std::strtod(p, &end);
        const char expected = a < 2 ? ',' : '\0';
        if (end == p || *end != expected || !std::isfinite(v[a]))
            throw prt::Error(option + ": expected X,Y,Z with three finite numbers, got \"" + text + "\"");
        p = end + 1;
    }
    return v;
}

constexpr const char* k_description =
    R"(Generate a synthetic point model with exact ground truth and write it as a pool.

Shapes (y is up; every shape is centred at the origin before --scale and --offset):
  sphere   radius --radius; normals outward.
  torus    centre circle of radius --major in the xz-plane, tube radius --minor (< --major),
           axis y; normals outward.
  cube     axis-aligned, edge --edge; points on the 6 faces, each with its face normal (sharp edges).
  plane    square of side --size in the plane y = 0, normal +y.
  ring     cylindrical band about y: inner radius --radius, wall --thickness, height --height
           (|y| <= height/2); inner wall (normals towards the axis), outer wall and top rim are
           sampled, the bottom is not: a mirror band for the cardioid caustic (thesis Fig. 5.3a).
  room     closed box of side --size seen from inside (floor, ceiling, 4 walls, normals inward)
           holding a sphere (radius 0.2 size) and a cube (edge 0.3 size, turned 25 degrees about y),
           both resting on the floor, normals outward; the cube's bottom face is not sampled.
           Parts are colored so each is identifiable: red left wall (x-), green right wall (x+).

Sampling: exactly --points points, uniform by area: points go to faces/patches in proportion to
their area (largest remainders), and each patch maps [0,1)^2 to its surface with an
area-preserving map (sphere: Archimedes; torus: inverse CDF of its area element) fed by Roberts' R2
low-discrepancy sequence (blue-noise-like spacing, --sampling r2) or independent uniform random
numbers (--sampling random). The output depends only on the options and --seed, never on --threads.

The pool's provenance records the shape and every parameter (prt::synth::shape_from_provenance
rebuilds the exact surface for error measurements), plus each part's point range and color.

Scan mode (--scan): instead of sampling, a virtual terrestrial laser scanner scans the shape, and the
points are its returns, as a real scan's (issue 15): dense along each scan line, sparser across
lines, thinning with range and incidence, with no normals. The head turns about --scan-axis in
azimuth steps of --line-step degrees; at each azimuth it sweeps a vertical scan line in elevation
steps of --sample-step degrees (anisotropy: their ratio; angles are multiples of the steps). From
outside the shape's bounding box the field is the cone of its bounding sphere; from inside it (the
room, the ring's hole) the whole sphere but a --blind-cone below. Each ray's first hit is exact
(prt::synth::first_hit). A hit at an incidence beyond --max-incidence gives no return; --dropout
loses steep returns at random (probability dropout x ((1 - cos i) / (1 - cos max))^2); the return
moves along its ray by Gaussian range noise (sigma --range-noise x size + --range-noise-per-range x
range, truncated at 4 sigma); --outliers moves that fraction of returns (exactly, rounded) along
their ray by 5-25 % of the model size, either sign (mixed pixels; towards the scanner at most to
10 % of the range), and --uniform-outliers appends
points uniform in the bounding box grown by 10 %. Every point gets an intensity, albedo x
cos(incidence) x (1 + --intensity-noise x N(0,1)) (albedo 0.8; the room's parts: their color's
luminance). Scanners: --scanner X,Y,Z (repeatable) or --scanners N default ones: outside at 3x the
model size from its centre, azimuth 30 + i 360/N degrees (0: +z, 90: +x), elevation 35; in the room
at (0.3 sin t, 0.05, 0.3 cos t) x size from its centre, t = i 360/N degrees. A scanner inside a
solid, outside the room or on the surface is an error. Each is written to the pool's sensors section (normals estimated later, e.g.
by prt-import, point toward it), and with several scanners each point's scan_ids entry names its
scanner. The provenance records every scan parameter, each scanner's field and counts (rays,
misses, dropped, returns), per-part returns and the outliers' indices; the counts are printed.

  prt-synth room --scan --range-noise 0.0005 --outliers 0.01 -o scan.pool
  prt-import scan.pool -o model.pool     (outlier removal, normals toward the sensors)

Scan-mode options are usage errors without --scan; --points, --sampling and --noise are usage
errors with it.)";

using ull = unsigned long long;

/// Runs `validate`; its prt::Error comes out as "invalid option: ...".
template <class F>
void check_options(F&& validate) {
    try {
        validate();
    } catch (const prt::Error& e) {
        throw prt::Error(std::string("invalid option: ") + e.what());
    }
}

/// The command line of prt-synth.
struct Cli {
    std::string shape_name;
    std::uint64_t points = 100000;
    double radius = 1.0, major = 1.0, minor = 0.25, edge = 2.0, size = 2.0;
    double noise = 0.0, scale = 1.0, thickness = 0.02, height = 0.4;
    std::vector<double> offset{0, 0, 0};
    std::uint64_t seed = 1;
    std::string sampling = "r2";
    std::string colors = "auto";
    unsigned threads = 0;
    // Scan mode.
    bool scan_mode = false, scan_normals = false;
    std::vector<std::string> scanner_texts;
    std::size_t scanner_count = 1;
    std::vector<double> scan_axis{0, 1, 0};
    prt::synth::ScanOptions scan_defaults;
    double sample_step = scan_defaults.sample_step_degrees, line_step = scan_defaults.line_step_degrees;
    double blind_cone = scan_defaults.blind_cone_degrees, max_incidence = scan_defaults.max_incidence_degrees;
    double dropout = 0, range_noise = 0, range_noise_per_range = 0, outliers = 0, uniform_outliers = 0;
    double intensity_noise = scan_defaults.intensity_noise;
    CLI::Option *o_points = nullptr, *o_sampling = nullptr, *o_noise = nullptr, *o_scanner = nullptr,
                *o_scanners = nullptr, *o_sample_step = nullptr, *o_line_step = nullptr;
    std::vector<CLI::Option*> scan_only;

    void declare(CLI::App& app);
    void declare_scan(CLI::App& app);
    void check_applies(const std::vector<std::pair<CLI::Option*, std::vector<std::string>>>& applies) const;
    prt::synth::SynthOptions synth_options() const;
    prt::synth::ScanOptions scan_options(const prt::synth::SynthOptions& o) const;
};

void Cli::declare(CLI::App& app) {
    app.add_option("shape", shape_name, "sphere, torus, cube, plane, room or ring")
        ->required()
        ->check(CLI::IsMember({"sphere", "torus", "cube", "plane", "room", "ring"}));
    o_points = app.add_option("-n,--points", points, "Number of points, exactly (not with --scan)")
                   ->check(CLI::Range(std::uint64_t{1}, prt::synth::k_max_points));
    auto* o_radius = app.add_option("--radius", radius, "sphere: radius; ring: inner radius");
    auto* o_thickness = app.add_option("--thickness", thickness, "ring: wall thickness");
    auto* o_height = app.add_option("--height", height, "ring: height of the band");
    auto* o_major = app.add_option("--major", major, "torus: major radius (centre circle)");
    auto* o_minor = app.add_option("--minor", minor, "torus: minor radius (tube), < --major");
    auto* o_edge = app.add_option("--edge", edge, "cube: edge length");
    auto* o_size = app.add_option("--size", size, "plane: side of the square; room: inner edge of the box");
    o_noise =
        app.add_option("--noise", noise,
                       "Gaussian displacement along the normal, standard deviation as a fraction of the "
                       "model size (largest bounding-box extent), truncated at 4 sigma; in [0, 1] (not "
                       "with --scan: see --range-noise)");
    app.add_option("--scale", scale, "Uniform scale applied to positions (normals unchanged), > 0");
    app.add_option("--offset", offset, "X,Y,Z added to positions after --scale (normals unchanged)")
        ->delimiter(',')
        ->expected(3);
    app.add_option("--seed", seed, "Seed of the sampling shifts, random numbers and noise");
    o_sampling = app.add_option("--sampling", sampling,
                                "r2 (low-discrepancy) or random (independent uniform) (not with --scan)")
                     ->check(CLI::IsMember({"r2", "random"}));
    app.add_option("--colors", colors,
                   "auto (room: parts, others: none), none, parts (each part or cube face its color), normal "
                   "(normal as RGB) or R,G,B (0-255, every point)");
    app.add_option("--threads", threads, "Worker threads (0 = all cores); the output does not depend on it");
    declare_scan(app);
    // Shape parameters that do not apply to the chosen shape are usage errors.
    app.final_callback([this, o_radius, o_thickness, o_height, o_major, o_minor, o_edge, o_size]() {
        check_applies({{o_radius, {"sphere", "ring"}},
                       {o_thickness, {"ring"}},
                       {o_height, {"ring"}},
                       {o_major, {"torus"}},
                       {o_minor, {"torus"}},
                       {o_edge, {"cube"}},
                       {o_size, {"plane", "room"}}});
    });
}

void Cli::declare_scan(CLI::App& app) {
    app.add_flag("--scan", scan_mode,
                 "Scan the shape with a virtual laser scanner instead of sampling it (see above)");
    auto* g = app.add_option_group("Scan mode (--scan)");
    o_scanner = g->add_option("--scanner", scanner_texts,
                              "X,Y,Z: a scanner position, world frame (repeatable: one scan each); default: "
                              "--scanners default placements");
    o_scanners = g->add_option("--scanners", scanner_count,
                               "Number of default scanner placements (not with --scanner)")
                     ->check(CLI::Range(std::size_t{1}, std::size_t{prt::pool::k_max_sensors}));
    scan_only.push_back(
        g->add_option("--scan-axis", scan_axis, "X,Y,Z: the scanner head's rotation axis (up), non-zero")
            ->delimiter(',')
            ->expected(3));
    o_sample_step = g->add_option("--sample-step", sample_step,
                                  "Degrees between samples along a scan line (elevation), in (0, 90]")
                        ->default_str("0.025 (room: 0.2)");
    o_line_step = g->add_option("--line-step", line_step, "Degrees between scan lines (azimuth), in (0, 360]")
                      ->default_str("4 x --sample-step");
    scan_only.push_back(
        g->add_option("--blind-cone", blind_cone,
                      "Half angle in degrees of the unscanned cone below the scanner (full-sphere "
                      "fields: the room), in [0, 90)"));
    scan_only.push_back(
        g->add_option("--max-incidence", max_incidence,
                      "No return where the angle between ray and normal exceeds this, degrees, in "
                      "(0, 90]"));
    scan_only.push_back(
        g->add_option("--dropout", dropout,
                      "Probability of losing a return at --max-incidence, falling to 0 at normal "
                      "incidence as ((1 - cos i) / (1 - cos max))^2; in [0, 1]"));
    scan_only.push_back(g->add_option("--range-noise", range_noise,
                                      "Gaussian noise along the ray, sigma as a fraction of the model size, "
                                      "truncated at 4 sigma; in [0, 1]"));
    scan_only.push_back(g->add_option("--range-noise-per-range", range_noise_per_range,
                                      "Added sigma per unit of range (e.g. 1e-4: 0.1 mm per m); in [0, 1]"));
    scan_only.push_back(
        g->add_option("--outliers", outliers,
                      "Fraction of returns moved along their ray by 5-25 % of the model size, "
                      "either sign (mixed pixels); in [0, 1]"));
    scan_only.push_back(
        g->add_option("--uniform-outliers", uniform_outliers,
                      "Points uniform in the bounding box grown by 10 %, as a fraction of the "
                      "returns, appended; in [0, 1]"));
    scan_only.push_back(
        g->add_option("--intensity-noise", intensity_noise,
                      "Relative Gaussian noise of the intensity albedo x cos(incidence); in [0, 1]"));
    scan_only.push_back(
        g->add_flag("--scan-normals", scan_normals,
                    "Write the true normal of each return (for tests: real scans have none)"));
    for (CLI::Option* opt : {o_scanner, o_scanners, o_sample_step, o_line_step}) scan_only.push_back(opt);
}

void Cli::check_applies(const std::vector<std::pair<CLI::Option*, std::vector<std::string>>>& applies) const {
    if (scan_mode) {
        for (CLI::Option* opt : {o_points, o_sampling, o_noise})
            if (opt->count() > 0) throw CLI::ValidationError(opt->get_name(), "does not apply to --scan");
        if (o_scanner->count() > 0 && o_scanners->count() > 0)
            throw CLI::ValidationError("--scanners", "give either --scanner positions or --scanners N");
    } else {
        for (CLI::Option* opt : scan_only)
            if (opt->count() > 0) throw CLI::ValidationError(opt->get_name(), "applies to --scan only");
    }
    for (const auto& [option, shapes] : applies)
        if (option->count() > 0 && std::find(shapes.begin(), shapes.end(), shape_name) == shapes.end())
            throw CLI::ValidationError(option->get_name(), "does not apply to shape " + shape_name);
}

prt::synth::SynthOptions Cli::synth_options() const {
    using namespace prt::synth;
    SynthOptions o;
    o.shape.kind = shape_kind(shape_name);
    o.shape.sphere.radius = radius;
    o.shape.torus = {major, minor};
    o.shape.cube.edge = edge;
    o.shape.plane.size = size;
    o.shape.ring = {radius, thickness, height};
    if (o.shape.kind == ShapeKind::room) {
        if (!(std::isfinite(size) && size > 0))
            throw prt::Error("invalid option: room size must be a finite number > 0, got " +
                             std::to_string(size));
        o.shape.room = Room::standard(size);
    }
    o.shape.scale = scale;
    o.shape.offset = {offset[0], offset[1], offset[2]};
    o.count = points;
    o.noise = noise;
    o.seed = seed;
    o.sampling = sampling == "random" ? Sampling::random : Sampling::r2;
    o.threads = threads;
    if (colors == "auto") {
        o.colors = o.shape.kind == ShapeKind::room ? ColorMode::parts : ColorMode::none;
    } else if (colors == "none") {
        o.colors = ColorMode::none;
    } else if (colors == "parts") {
        o.colors = ColorMode::parts;
    } else if (colors == "normal") {
        o.colors = ColorMode::normal;
    } else {
        unsigned r = 0, g = 0, b = 0;
        char tail = 0;
        if (std::sscanf(colors.c_str(), "%u,%u,%u%c", &r, &g, &b, &tail) != 3 || r > 255 || g > 255 ||
            b > 255)
            throw prt::Error(
                "--colors: expected auto, none, parts, normal or R,G,B with 0-255 components, got \"" +
                colors + "\"");
        o.colors = ColorMode::constant;
        o.color = {std::uint8_t(r), std::uint8_t(g), std::uint8_t(b), 255};
    }
    return o;
}

prt::synth::ScanOptions Cli::scan_options(const prt::synth::SynthOptions& o) const {
    using namespace prt::synth;
    ScanOptions so;
    so.shape = o.shape;
    check_options([&] { validate(so.shape); });
    for (const std::string& t : scanner_texts) so.scanners.push_back(parse_vec3("--scanner", t));
    if (so.scanners.empty()) so.scanners = default_scanners(so.shape, scanner_count);
    so.axis = {scan_axis[0], scan_axis[1], scan_axis[2]};
    so.sample_step_degrees =
        o_sample_step->count() > 0 ? sample_step : (o.shape.kind == ShapeKind::room ? 0.2 : 0.025);
    so.line_step_degrees = o_line_step->count() > 0 ? line_step : 4 * so.sample_step_degrees;
    so.blind_cone_degrees = blind_cone;
    so.max_incidence_degrees = max_incidence;
    so.dropout = dropout;
    so.range_noise = range_noise;
    so.range_noise_per_range = range_noise_per_range;
    so.outliers = outliers;
    so.uniform_outliers = uniform_outliers;
    so.intensity_noise = intensity_noise;
    so.normals = scan_normals;
    so.colors = o.colors;
    so.color = o.color;
    so.seed = seed;
    so.threads = threads;
    check_options([&] { validate(so); });
    return so;
}

void scan_step(prt::tool::PoolStep& step, const Cli& cli, const prt::synth::SynthOptions& o) {
    using namespace prt::synth;
    const ScanOptions so = cli.scan_options(o);
    step.check_output_folder();
    ScanResult result;
    {
        std::optional<prt::tool::Progress> bar;
        result = scan(so, [&](std::uint64_t done, std::uint64_t total) {
            if (!bar) bar.emplace("prt-synth: scanning", total, step.quiet());
            bar->update(done);
        });
        if (bar) bar->finish();
    }
    const double t0 = prt::tool::now_seconds();
    prt::pre::write_point_sections(result.cloud, step.writer());
    const std::uint64_t bytes = step.write(result.parameters_json);
    std::uint64_t rays = 0, misses = 0, grazing = 0, dropped = 0;
    for (const ScannerStats& st : result.scanners) {
        rays += st.rays;
        misses += st.misses;
        grazing += st.dropped_grazing;
        dropped += st.dropped_dropout;
    }
    step.note(
        "prt-synth: %s scan, %zu scanner%s: %llu rays, %llu missed, %llu beyond %g degrees incidence, "
        "%llu dropped; %llu returns (%zu displaced outliers) + %llu uniform outliers = %llu points",
        cli.shape_name.c_str(), result.scanners.size(), result.scanners.size() == 1 ? "" : "s", ull(rays),
        ull(misses), ull(grazing), so.max_incidence_degrees, ull(dropped), ull(result.returns),
        result.outlier_indices.size(), ull(result.uniform_count), ull(result.cloud.size()));
    step.note("prt-synth: wrote %s: %.1f MB in %.3f s", step.output_path().c_str(), double(bytes) / 1e6,
              prt::tool::now_seconds() - t0);
}

void sample_step(prt::tool::PoolStep& step, const Cli& cli, const prt::synth::SynthOptions& o) {
    using namespace prt::synth;
    // Everything is checked before the (possibly long) sampling starts.
    check_options([&] { validate(o); });
    step.check_output_folder();
    SynthResult result;
    {
        prt::tool::Progress bar("prt-synth: sampling", o.count, step.quiet());
        result = synthesize(o, [&](std::uint64_t done, std::uint64_t) { bar.update(done); });
        bar.finish();
    }
    const double t0 = prt::tool::now_seconds();
    prt::pre::write_point_sections(result.cloud, step.writer());
    const std::uint64_t bytes = step.write(result.parameters_json);
    step.note("prt-synth: wrote %s: %s, %llu points, %zu part%s, noise sigma %g, %.1f MB in %.3f s",
              step.output_path().c_str(), cli.shape_name.c_str(), ull(o.count), result.parts.size(),
              result.parts.size() == 1 ? "" : "s", result.noise_sigma, double(bytes) / 1e6,
              prt::tool::now_seconds() - t0);
}

}  // namespace

int main(int argc, char** argv) {
    Cli cli;
    prt::tool::PoolStep step("prt-synth", k_description, prt::tool::PoolStep::generator_help());
    return step.run(
        argc, argv, [&](CLI::App& app) { cli.declare(app); },
        [&](prt::tool::PoolStep& s) {
            const prt::synth::SynthOptions o = cli.synth_options();
            if (cli.scan_mode)
                scan_step(s, cli, o);
            else
                sample_step(s, cli, o);
        });
}
