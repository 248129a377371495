#include "synth.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numeric>

#include "prt/error.h"
#include "prt/parallel.h"
#include "synth_random.h"

namespace prt::synth {
namespace {

constexpr double k_pi = 3.14159265358979323846;

using namespace detail;

// Roberts' R2 sequence: x_n = frac(s + n * (1/g, 1/g^2)), g the plastic number (x^3 = x + 1),
// in 64-bit fixed point so it is exact for any n (wrap-around is the fractional part).
constexpr std::uint64_t k_r2_a1 = 0xC13FA9A902A6328Full;  // round(2^64 / 1.324717957244746)
constexpr std::uint64_t k_r2_a2 = 0x91E10DA5C79E7B1Dull;  // round(2^64 / 1.324717957244746^2)

/// Solves theta + k sin(theta) = 2 pi u for theta in [0, 2 pi): the inverse of the torus's
/// area-weighted marginal CDF (area element r (R + r cos theta) dtheta dphi, k = r / R < 1).
/// Halley's method (cubic convergence: 1 to 3 steps for k <= 0.9) kept inside a bisection bracket,
/// valid since f' = 1 + k cos(theta) > 0. Accurate to ~1e-15 for k <= 0.9, ~1e-13 for k = 0.999.
double torus_theta(double u, double k) {
    const double t = 2 * k_pi * u;
    double lo = 0, hi = 2 * k_pi;
    double theta = t - k * std::sin(t) / (1 + k * std::cos(t));  // one Newton step from theta = t
    for (int i = 0; i < 64; ++i) {
        const double s = std::sin(theta), c = std::cos(theta);
        const double f = theta + k * s - t;
        if (f > 0)
            hi = theta;
        else
            lo = theta;
        const double d1 = 1 + k * c, d2 = -k * s;
        double next = theta - 2 * f * d1 / (2 * d1 * d1 - f * d2);
        if (!(next >= lo && next <= hi)) next = 0.5 * (lo + hi);  // the step left the bracket
        const double moved = std::fabs(next - theta);
        theta = next;
        if (moved < 1e-9) break;  // the next error is ~moved^3: below double precision
    }
    return theta;
}

// ---- Patches: pieces of surface with an area-preserving map from [0,1)^2 ------------------------

struct Patch {
    enum Type { square, sphere, torus, cylinder, annulus } type = square;
    int part = 0;                       ///< index into the part list
    double area = 0;                    ///< local frame
    Vec3 center{};                      ///< square centre / sphere centre
    Vec3 axis_u{}, axis_v{}, normal{};  ///< square: unit edge directions and normal
    double half_u = 0, half_v = 0;      ///< square half extents
    double radius = 0;                  ///< sphere radius / torus minor radius
    double major = 0;                   ///< torus major radius
    double height = 0;                  ///< cylinder height (|y| <= height / 2); annulus plane y
    double sign = 1;                    ///< cylinder: +1 normals outward, -1 towards the axis
    double outer = 0;                   ///< annulus outer radius (inner: radius)
};

Patch square_patch(int part, const Vec3& center, const Vec3& u, const Vec3& v, const Vec3& n, double half_u,
                   double half_v) {
    Patch p;
    p.type = Patch::square;
    p.part = part;
    p.center = center;
    p.axis_u = u;
    p.axis_v = v;
    p.normal = n;
    p.half_u = half_u;
    p.half_v = half_v;
    p.area = 4 * half_u * half_v;
    return p;
}

Patch sphere_patch(int part, const Vec3& center, double radius) {
    Patch p;
    p.type = Patch::sphere;
    p.part = part;
    p.center = center;
    p.radius = radius;
    p.area = 4 * k_pi * radius * radius;
    return p;
}

/// The 6 faces of an axis-aligned cube of half edge h about `center`, turned by `yaw` about y,
/// normals outward (sign +1) or inward (-1); face f = 2 axis + (negative side). Axes (u, v, n)
/// are right-handed for outward normals.
void box_faces(std::vector<Patch>& out, const Vec3& center, double h, double yaw, double sign,
               const int (&part_of_face)[6], bool skip_bottom) {
    for (int face = 0; face < 6; ++face) {
        if (skip_bottom && face == 3) continue;  // -y
        const int axis = face / 2;
        const double side = face % 2 ? -1.0 : 1.0;
        Vec3 n{0, 0, 0}, u{0, 0, 0}, v{0, 0, 0};
        n[axis] = side;
        u[(axis + 1) % 3] = 1;
        v[(axis + 2) % 3] = side;
        out.push_back(square_patch(part_of_face[face], add(center, rotate_y(mul(n, h), yaw)),
                                   rotate_y(u, yaw), rotate_y(v, yaw), rotate_y(mul(n, sign), yaw), h, h));
    }
}

struct Part {
    std::string name;
    pool::Rgba8 color;
};

void build_patches(const SynthOptions& o, std::vector<Patch>& patches, std::vector<Part>& parts) {
    const Shape& s = o.shape;
    switch (s.kind) {
        case ShapeKind::sphere:
            parts.push_back({"sphere", o.color});
            patches.push_back(sphere_patch(0, {0, 0, 0}, s.sphere.radius));
            break;
        case ShapeKind::torus: {
            parts.push_back({"torus", o.color});
            Patch p;
            p.type = Patch::torus;
            p.part = 0;
            p.radius = s.torus.minor_radius;
            p.major = s.torus.major_radius;
            p.area = 4 * k_pi * k_pi * p.major * p.radius;
            patches.push_back(p);
            break;
        }
        case ShapeKind::cube: {
            for (int f = 0; f < 6; ++f) parts.push_back({cube_face_name(f), cube_face_color(f)});
            static constexpr int k_identity[6] = {0, 1, 2, 3, 4, 5};
            box_faces(patches, {0, 0, 0}, 0.5 * s.cube.edge, 0.0, 1.0, k_identity, false);
            break;
        }
        case ShapeKind::plane:
            parts.push_back({"plane", o.color});
            patches.push_back(square_patch(0, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}, 0.5 * s.plane.size,
                                           0.5 * s.plane.size));
            break;
        case ShapeKind::ring: {
            const Ring& r = s.ring;
            parts.push_back({"inner", o.color});
            parts.push_back({"outer", o.color});
            parts.push_back({"top", o.color});
            const double outer = r.radius + r.thickness;
            for (int side = 0; side < 2; ++side) {
                Patch p;
                p.type = Patch::cylinder;
                p.part = side == 0 ? k_ring_inner : k_ring_outer;
                p.radius = side == 0 ? r.radius : outer;
                p.height = r.height;
                p.sign = side == 0 ? -1.0 : 1.0;
                p.area = 2 * k_pi * p.radius * r.height;
                patches.push_back(p);
            }
            Patch top;
            top.type = Patch::annulus;
            top.part = k_ring_top;
            top.radius = r.radius;
            top.outer = outer;
            top.height = 0.5 * r.height;
            top.area = k_pi * (outer * outer - r.radius * r.radius);
            patches.push_back(top);
            break;
        }
        case ShapeKind::room: {
            const Room& r = s.room;
            for (int p = 0; p < k_room_part_count; ++p)
                parts.push_back({room_part_name(p), room_part_color(p)});
            // Walls in part order (floor, ceiling, left, right, back, front), normals inward.
            static constexpr int k_wall_face[6] = {3, 2, 1, 0, 5, 4};  // part -> box face
            std::vector<Patch> walls;
            static constexpr int k_face_part[6] = {k_room_right_wall, k_room_left_wall,  k_room_ceiling,
                                                   k_room_floor,      k_room_front_wall, k_room_back_wall};
            box_faces(walls, {0, 0, 0}, 0.5 * r.size, 0.0, -1.0, k_face_part, false);
            for (int part = 0; part < 6; ++part) patches.push_back(walls[k_wall_face[part]]);
            patches.push_back(sphere_patch(k_room_sphere, r.sphere_center, r.sphere_radius));
            static constexpr int k_cube_part[6] = {k_room_cube, k_room_cube, k_room_cube,
                                                   k_room_cube, k_room_cube, k_room_cube};
            box_faces(patches, r.cube_center, 0.5 * r.cube_edge, r.cube_yaw_degrees * k_pi / 180.0, 1.0,
                      k_cube_part, true);
            break;
        }
    }
}

/// Largest-remainder apportionment of `total` points to patches by area (ties: lower index).
std::vector<std::uint64_t> allocate(const std::vector<Patch>& patches, std::uint64_t total) {
    double area = 0;
    for (const Patch& p : patches) area += p.area;
    std::vector<std::uint64_t> counts(patches.size());
    std::vector<std::pair<double, std::size_t>> remainders;
    std::uint64_t assigned = 0;
    for (std::size_t i = 0; i < patches.size(); ++i) {
        const double exact = static_cast<double>(total) * (patches[i].area / area);
        counts[i] = static_cast<std::uint64_t>(std::floor(exact));
        assigned += counts[i];
        remainders.push_back({exact - std::floor(exact), i});
    }
    std::stable_sort(remainders.begin(), remainders.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    for (std::size_t k = 0; assigned < total; k = (k + 1) % remainders.size(), ++assigned)
        ++counts[remainders[k].second];
    return counts;
}

/// Point `index` of `patch` at parameters (u, v): position and unit normal, local frame.
void evaluate(const Patch& p, double u, double v, Vec3& position, Vec3& normal) {
    switch (p.type) {
        case Patch::square:
            position = add(p.center,
                           add(mul(p.axis_u, (2 * u - 1) * p.half_u), mul(p.axis_v, (2 * v - 1) * p.half_v)));
            normal = p.normal;
            break;
        case Patch::sphere: {
            // Archimedes: the height along the axis is uniform for area-uniform points.
            const double y = 1 - 2 * u;
            const double ring = std::sqrt(std::max(0.0, 1 - y * y));
            const double phi = 2 * k_pi * v;
            normal = {ring * std::cos(phi), y, ring * std::sin(phi)};
            position = add(p.center, mul(normal, p.radius));
            break;
        }
        case Patch::torus: {
            const double theta = torus_theta(u, p.radius / p.major);
            const double phi = 2 * k_pi * v;
            const double ct = std::cos(theta), st = std::sin(theta), cp = std::cos(phi), sp = std::sin(phi);
            normal = {ct * cp, st, ct * sp};
            const double ring = p.major + p.radius * ct;
            position = {ring * cp, p.radius * st, ring * sp};
            break;
        }
        case Patch::cylinder: {
            // Area-preserving: the angle and the height are both uniform.
            const double phi = 2 * k_pi * u;
            normal = {p.sign * std::cos(phi), 0.0, p.sign * std::sin(phi)};
            position = {p.radius * std::cos(phi), (v - 0.5) * p.height, p.radius * std::sin(phi)};
            break;
        }
        case Patch::annulus: {
            // Area-preserving: rho^2 uniform between the radii.
            const double rho = std::sqrt(p.radius * p.radius + u * (p.outer * p.outer - p.radius * p.radius));
            const double phi = 2 * k_pi * v;
            normal = {0, 1, 0};
            position = {rho * std::cos(phi), p.height, rho * std::sin(phi)};
            break;
        }
    }
}

}  // namespace

pool::Rgba8 normal_color(const Vec3& n) {
    auto c = [](double x) {
        return static_cast<std::uint8_t>(std::lround(std::clamp((x + 1) * 0.5, 0.0, 1.0) * 255));
    };
    return {c(n[0]), c(n[1]), c(n[2]), 255};
}

const char* sampling_name(Sampling s) {
    return s == Sampling::r2 ? "r2" : "random";
}

const char* color_mode_name(ColorMode m) {
    switch (m) {
        case ColorMode::none:
            return "none";
        case ColorMode::parts:
            return "parts";
        case ColorMode::normal:
            return "normal";
        case ColorMode::constant:
            return "constant";
    }
    return "unknown";
}

void validate(const SynthOptions& o) {
    validate(o.shape);
    if (o.count == 0 || o.count > k_max_points)
        throw Error("point count must be in [1, " + std::to_string(k_max_points) + "], got " +
                    std::to_string(o.count));
    if (!(std::isfinite(o.noise) && o.noise >= 0 && o.noise <= 1)) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", o.noise);
        throw Error(std::string("noise must be in [0, 1] (a fraction of the model size), got ") + buf);
    }
    if (o.threads > 4096) throw Error("threads must be at most 4096, got " + std::to_string(o.threads));
}

SynthResult synthesize(const SynthOptions& o,
                       const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    validate(o);

    std::vector<Patch> patches;
    std::vector<Part> parts;
    build_patches(o, patches, parts);
    const std::vector<std::uint64_t> counts = allocate(patches, o.count);
    std::vector<std::uint64_t> first(patches.size() + 1, 0);
    for (std::size_t i = 0; i < patches.size(); ++i) first[i + 1] = first[i] + counts[i];
    std::vector<std::array<std::uint64_t, 2>> shift(patches.size());
    for (std::size_t i = 0; i < patches.size(); ++i)
        shift[i] = {hash(o.seed, k_stream_shift, i, 0), hash(o.seed, k_stream_shift, i, 1)};

    Shape local = o.shape;
    local.scale = 1;
    local.offset = {0, 0, 0};
    const double sigma_local = o.noise * shape_size(local);

    SynthResult result;
    result.noise_sigma = sigma_local * o.shape.scale;
    pre::PointCloud& cloud = result.cloud;
    cloud.flags = pool::k_model_synthetic;
    const std::size_t n = static_cast<std::size_t>(o.count);
    cloud.positions.resize(n);
    cloud.normals.resize(n);
    if (o.colors != ColorMode::none) cloud.colors.resize(n);

    std::vector<pool::Rgba8> part_color(parts.size());
    for (std::size_t i = 0; i < parts.size(); ++i)
        part_color[i] = o.colors == ColorMode::constant ? o.color : parts[i].color;

    constexpr std::uint64_t k_chunk = 1 << 16;
    std::atomic<std::uint64_t> done{0};
    // The calling thread (worker 0) is the only one that calls `progress`.
    parallel_chunks(o.count, k_chunk, resolve_threads(o.threads),
                    [&](std::size_t begin, std::size_t end, unsigned worker) {
                        std::size_t patch =
                            std::upper_bound(first.begin(), first.end(), begin) - first.begin() - 1;
                        for (std::uint64_t i = begin; i < end; ++i) {
                            while (i >= first[patch + 1]) ++patch;
                            const Patch& p = patches[patch];
                            const std::uint64_t j = i - first[patch];
                            double u, v;
                            if (o.sampling == Sampling::r2) {
                                u = unit(shift[patch][0] + (j + 1) * k_r2_a1);
                                v = unit(shift[patch][1] + (j + 1) * k_r2_a2);
                            } else {
                                Stream s{hash(o.seed, k_stream_random, patch, j)};
                                u = s.uniform();
                                v = s.uniform();
                            }
                            Vec3 position{}, normal{};
                            evaluate(p, u, v, position, normal);
                            if (sigma_local > 0) {
                                Stream s{hash(o.seed, k_stream_noise, i)};
                                position = add(position, mul(normal, sigma_local * truncated_gaussian(s)));
                            }
                            cloud.positions[i] = add(mul(position, o.shape.scale), o.shape.offset);
                            cloud.normals[i] = {float(normal[0]), float(normal[1]), float(normal[2])};
                            if (o.colors == ColorMode::normal)
                                cloud.colors[i] = normal_color(normal);
                            else if (o.colors != ColorMode::none)
                                cloud.colors[i] = part_color[p.part];
                        }
                        const std::uint64_t total_done = done.fetch_add(end - begin) + (end - begin);
                        if (worker == 0 && progress) progress(total_done, o.count);
                    });
    if (progress) progress(o.count, o.count);

    // Parts in point order (a part's patches are consecutive).
    const double scale2 = o.shape.scale * o.shape.scale;
    for (std::size_t i = 0; i < patches.size(); ++i) {
        const int part = patches[i].part;
        if (result.parts.empty() || result.parts.back().name != parts[part].name) {
            result.parts.push_back({parts[part].name, first[i], 0, 0.0, part_color[part]});
        }
        result.parts.back().count += counts[i];
        result.parts.back().area += patches[i].area * scale2;
    }

    nlohmann::ordered_json j;
    j["shape"] = nlohmann::ordered_json::parse(shape_to_json(o.shape));
    j["points"] = o.count;
    j["sampling"] = sampling_name(o.sampling);
    j["seed"] = o.seed;
    j["noise"] = o.noise;
    j["noise_sigma"] = result.noise_sigma;
    j["noise_truncation"] = k_noise_truncation;
    j["colors"] = color_mode_name(o.colors);
    nlohmann::ordered_json jp = nlohmann::ordered_json::array();
    for (const PartRange& p : result.parts) {
        nlohmann::ordered_json e;
        e["name"] = p.name;
        e["first"] = p.first;
        e["count"] = p.count;
        e["area"] = p.area;
        e["color"] = {p.color.r, p.color.g, p.color.b};
        jp.push_back(e);
    }
    j["parts"] = jp;
    result.parameters_json = j.dump();
    return result;
}

}  // namespace prt::synth
