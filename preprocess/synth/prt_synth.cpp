// prt-synth: analytic point sets with exact ground truth, written as pools (issue 2, synthetic models).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "point_cloud.h"
#include "prt/formats/pool.h"
#include "prt/tool.h"
#include "synth.h"

namespace {

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
rebuilds the exact surface for error measurements), plus each part's point range and color.)";

}  // namespace

int main(int argc, char** argv) {
    std::string shape_name;
    std::string output;
    std::uint64_t points = 100000;
    double radius = 1.0, major = 1.0, minor = 0.25, edge = 2.0, size = 2.0;
    double noise = 0.0, scale = 1.0, thickness = 0.02, height = 0.4;
    std::vector<double> offset{0, 0, 0};
    std::uint64_t seed = 1;
    std::string sampling = "r2";
    std::string colors = "auto";
    unsigned threads = 0;

    return prt::tool::run(
        argc, argv, "prt-synth", k_description,
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("shape", shape_name, "sphere, torus, cube, plane, room or ring")
                ->required()
                ->check(CLI::IsMember({"sphere", "torus", "cube", "plane", "room", "ring"}));
            app.add_option("-o,--output", output, "Pool file to write (replaced atomically)")->required();
            app.add_option("-n,--points", points, "Number of points, exactly")
                ->check(CLI::Range(std::uint64_t{1}, prt::synth::k_max_points));
            auto* o_radius = app.add_option("--radius", radius, "sphere: radius; ring: inner radius")
                                 ->capture_default_str();
            auto* o_thickness =
                app.add_option("--thickness", thickness, "ring: wall thickness")->capture_default_str();
            auto* o_height = app.add_option("--height", height, "ring: height of the band")->capture_default_str();
            auto* o_major = app.add_option("--major", major, "torus: major radius (centre circle)");
            auto* o_minor = app.add_option("--minor", minor, "torus: minor radius (tube), < --major");
            auto* o_edge = app.add_option("--edge", edge, "cube: edge length");
            auto* o_size =
                app.add_option("--size", size, "plane: side of the square; room: inner edge of the box");
            app.add_option("--noise", noise,
                           "Gaussian displacement along the normal, standard deviation as a fraction of the "
                           "model size (largest bounding-box extent), truncated at 4 sigma; in [0, 1]");
            app.add_option("--scale", scale, "Uniform scale applied to positions (normals unchanged), > 0");
            app.add_option("--offset", offset, "X,Y,Z added to positions after --scale (normals unchanged)")
                ->delimiter(',')
                ->expected(3);
            app.add_option("--seed", seed, "Seed of the sampling shifts, random numbers and noise");
            app.add_option("--sampling", sampling, "r2 (low-discrepancy) or random (independent uniform)")
                ->check(CLI::IsMember({"r2", "random"}));
            app.add_option(
                "--colors", colors,
                "auto (room: parts, others: none), none, parts (each part or cube face its color), "
                "normal (normal as RGB) or R,G,B (0-255, every point)");
            app.add_option("--threads", threads,
                           "Worker threads (0 = all cores); the output does not depend on it");
            // Shape parameters that do not apply to the chosen shape are usage errors.
            app.final_callback([=, &shape_name]() {
                struct Applies {
                    CLI::Option* option;
                    std::vector<std::string> shapes;
                };
                for (const Applies& a :
                     {Applies{o_radius, {"sphere", "ring"}}, Applies{o_thickness, {"ring"}}, Applies{o_height, {"ring"}},
                      Applies{o_major, {"torus"}}, Applies{o_minor, {"torus"}},
                      Applies{o_edge, {"cube"}}, Applies{o_size, {"plane", "room"}}})
                    if (a.option->count() > 0 &&
                        std::find(a.shapes.begin(), a.shapes.end(), shape_name) == a.shapes.end())
                        throw CLI::ValidationError(a.option->get_name(),
                                                   "does not apply to shape " + shape_name);
            });
        },
        [&](const prt::tool::CommonOptions& common) {
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
                        "--colors: expected auto, none, parts, normal or R,G,B with 0-255 components, got "
                        "\"" +
                        colors + "\"");
                o.colors = ColorMode::constant;
                o.color = {std::uint8_t(r), std::uint8_t(g), std::uint8_t(b), 255};
            }

            // Everything is checked before the (possibly long) sampling starts.
            try {
                validate(o);
            } catch (const prt::Error& e) {
                throw prt::Error(std::string("invalid option: ") + e.what());
            }
            const std::filesystem::path out_dir = std::filesystem::path(output).parent_path();
            if (!out_dir.empty() && !std::filesystem::is_directory(out_dir))
                throw prt::Error(output + ": cannot write: folder " + out_dir.string() + " does not exist");
            SynthResult result;
            {
                prt::tool::Progress bar("prt-synth: sampling", o.count, common.quiet);
                result = synthesize(o, [&](std::uint64_t done, std::uint64_t) { bar.update(done); });
                bar.finish();
            }
            const double t0 = prt::tool::now_seconds();
            prt::pool::PoolWriter writer;
            prt::pre::write_point_sections(result.cloud, writer);
            writer.add_provenance("prt-synth", PRT_VERSION, result.parameters_json);
            const std::uint64_t bytes = writer.write(output);
            prt::tool::note(
                common.quiet,
                "prt-synth: wrote %s: %s, %llu points, %zu part%s, noise sigma %g, %.1f MB in %.3f s",
                output.c_str(), shape_name.c_str(), static_cast<unsigned long long>(o.count),
                result.parts.size(), result.parts.size() == 1 ? "" : "s", result.noise_sigma,
                double(bytes) / 1e6, prt::tool::now_seconds() - t0);
        });
}
