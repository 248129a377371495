#include "analytic.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>

#include "prt/error.h"

namespace prt::synth {
namespace {

constexpr double k_pi = 3.14159265358979323846;

Vec3 add(const Vec3& a, const Vec3& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
Vec3 sub(const Vec3& a, const Vec3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
Vec3 mul(const Vec3& a, double s) {
    return {a[0] * s, a[1] * s, a[2] * s};
}
double dot(const Vec3& a, const Vec3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double norm(const Vec3& a) {
    return std::sqrt(dot(a, a));
}

/// Rotation about +y by `radians` (right-handed: +z turns towards +x).
Vec3 rotate_y(const Vec3& v, double radians) {
    const double c = std::cos(radians), s = std::sin(radians);
    return {c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]};
}

/// Exact closest point of an axis-aligned box [-h, h] (centred at the origin) to p.
/// Outside: the clamped point; inside: p pushed onto the face of the axis where it is farthest out.
/// The face returned (axis, sign) is the one of the largest |p_a| - h_a in both cases.
SurfacePoint closest_box(const Vec3& half, const Vec3& p) {
    Vec3 q;
    for (int a = 0; a < 3; ++a) q[a] = std::fabs(p[a]) - half[a];
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (q[a] > q[axis]) axis = a;
    const double sign = p[axis] < 0 ? -1.0 : 1.0;
    SurfacePoint r;
    r.normal = {0, 0, 0};
    r.normal[axis] = sign;
    r.part = 2 * axis + (sign < 0 ? 1 : 0);
    if (q[axis] > 0) {  // outside
        double outside2 = 0;
        for (int a = 0; a < 3; ++a) {
            r.point[a] = std::clamp(p[a], -half[a], half[a]);
            outside2 += std::max(q[a], 0.0) * std::max(q[a], 0.0);
        }
        r.signed_distance = std::sqrt(outside2);
    } else {  // inside or on the surface
        r.point = p;
        r.point[axis] = sign * half[axis];
        r.signed_distance = q[axis];
    }
    return r;
}

std::string number_text(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

[[noreturn]] void bad(const std::string& what, double value) {
    throw Error(what + ", got " + number_text(value));
}

void require_positive(const char* name, double v) {
    if (!(std::isfinite(v) && v > 0)) bad(std::string(name) + " must be a finite number > 0", v);
}

}  // namespace

const char* shape_name(ShapeKind kind) {
    switch (kind) {
        case ShapeKind::sphere:
            return "sphere";
        case ShapeKind::torus:
            return "torus";
        case ShapeKind::cube:
            return "cube";
        case ShapeKind::plane:
            return "plane";
        case ShapeKind::room:
            return "room";
        case ShapeKind::ring:
            return "ring";
    }
    return "unknown";
}

ShapeKind shape_kind(const std::string& name) {
    for (ShapeKind k :
         {ShapeKind::sphere, ShapeKind::torus, ShapeKind::cube, ShapeKind::plane, ShapeKind::room, ShapeKind::ring})
        if (name == shape_name(k)) return k;
    throw Error("unknown shape \"" + name + "\" (expected sphere, torus, cube, plane, room or ring)");
}

Room Room::standard(double size) {
    Room r;
    const double h = 0.5 * size;
    r.size = size;
    r.sphere_radius = 0.2 * size;
    r.sphere_center = {-0.2 * size, -h + r.sphere_radius, -0.1 * size};
    r.cube_edge = 0.3 * size;
    r.cube_center = {0.22 * size, -h + 0.5 * r.cube_edge, 0.12 * size};
    r.cube_yaw_degrees = 25.0;
    return r;
}

const char* room_part_name(int part) {
    static constexpr const char* k_names[k_room_part_count] = {
        "floor", "ceiling", "left_wall", "right_wall", "back_wall", "front_wall", "sphere", "cube"};
    return part >= 0 && part < k_room_part_count ? k_names[part] : "unknown";
}

pool::Rgba8 room_part_color(int part) {
    // Cornell-box-like: red left wall, green right wall (color bleeding), near-whites that still
    // differ per part so colors identify parts, a gold sphere and a blue cube.
    static constexpr pool::Rgba8 k_colors[k_room_part_count] = {
        {190, 190, 190, 255},  // floor
        {235, 235, 235, 255},  // ceiling
        {200, 40, 40, 255},    // left wall: red
        {40, 200, 40, 255},    // right wall: green
        {215, 215, 215, 255},  // back wall
        {170, 170, 200, 255},  // front wall
        {230, 190, 60, 255},   // sphere
        {60, 120, 220, 255},   // cube
    };
    return part >= 0 && part < k_room_part_count ? k_colors[part] : pool::Rgba8{0, 0, 0, 255};
}

int room_part_from_color(pool::Rgba8 c) {
    for (int p = 0; p < k_room_part_count; ++p) {
        const pool::Rgba8 k = room_part_color(p);
        if (k.r == c.r && k.g == c.g && k.b == c.b) return p;
    }
    return -1;
}

const char* cube_face_name(int face) {
    static constexpr const char* k_names[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
    return face >= 0 && face < 6 ? k_names[face] : "unknown";
}

pool::Rgba8 cube_face_color(int face) {
    static constexpr pool::Rgba8 k_colors[6] = {{220, 60, 60, 255}, {60, 200, 200, 255},
                                                {60, 200, 60, 255}, {200, 60, 200, 255},
                                                {60, 60, 220, 255}, {220, 220, 60, 255}};
    return face >= 0 && face < 6 ? k_colors[face] : pool::Rgba8{0, 0, 0, 255};
}

void validate(const Shape& s) {
    require_positive("scale", s.scale);
    for (double o : s.offset)
        if (!std::isfinite(o)) bad("offset must be finite", o);
    switch (s.kind) {
        case ShapeKind::sphere:
            require_positive("sphere radius", s.sphere.radius);
            break;
        case ShapeKind::torus:
            require_positive("torus major radius", s.torus.major_radius);
            require_positive("torus minor radius", s.torus.minor_radius);
            if (!(s.torus.minor_radius < s.torus.major_radius))
                bad("torus minor radius must be smaller than the major radius " +
                        number_text(s.torus.major_radius) + " (a ring torus)",
                    s.torus.minor_radius);
            break;
        case ShapeKind::cube:
            require_positive("cube edge", s.cube.edge);
            break;
        case ShapeKind::plane:
            require_positive("plane size", s.plane.size);
            break;
        case ShapeKind::ring:
            require_positive("ring radius", s.ring.radius);
            require_positive("ring thickness", s.ring.thickness);
            require_positive("ring height", s.ring.height);
            break;
        case ShapeKind::room: {
            const Room& r = s.room;
            require_positive("room size", r.size);
            require_positive("room sphere radius", r.sphere_radius);
            require_positive("room cube edge", r.cube_edge);
            for (double v : {r.sphere_center[0], r.sphere_center[1], r.sphere_center[2], r.cube_center[0],
                             r.cube_center[1], r.cube_center[2], r.cube_yaw_degrees})
                if (!std::isfinite(v)) bad("room object placement must be finite", v);
            const double h = 0.5 * r.size, tol = 1e-9 * r.size;
            for (int a = 0; a < 3; ++a)
                if (std::fabs(r.sphere_center[a]) + r.sphere_radius > h + tol)
                    bad("room sphere must lie inside the room (|centre| + radius <= size / 2)",
                        std::fabs(r.sphere_center[a]) + r.sphere_radius);
            const double yaw = r.cube_yaw_degrees * k_pi / 180.0, e = 0.5 * r.cube_edge;
            for (int corner = 0; corner < 8; ++corner) {
                const Vec3 local{corner & 1 ? e : -e, corner & 2 ? e : -e, corner & 4 ? e : -e};
                const Vec3 w = add(r.cube_center, rotate_y(local, yaw));
                for (int a = 0; a < 3; ++a)
                    if (std::fabs(w[a]) > h + tol)
                        bad("room cube must lie inside the room (corner coordinate)", w[a]);
            }
            const Vec3 local = rotate_y(sub(r.sphere_center, r.cube_center), -yaw);
            const double gap = closest(Cube{r.cube_edge}, local).signed_distance - r.sphere_radius;
            if (gap < -tol) bad("room sphere and cube must not overlap (gap between them)", gap);
            break;
        }
    }
}

SurfacePoint closest(const Sphere& s, const Vec3& p) {
    const double d = norm(p);
    SurfacePoint r;
    r.normal = d > 0 ? mul(p, 1.0 / d) : Vec3{0, 1, 0};  // the centre: every direction is nearest
    r.point = mul(r.normal, s.radius);
    r.signed_distance = d - s.radius;
    return r;
}

SurfacePoint closest(const Torus& t, const Vec3& p) {
    // The torus is the set of points at distance r from the centre circle, so the nearest surface
    // point lies on the segment from the nearest circle point through p (exact for r < R).
    const double q = std::hypot(p[0], p[2]);
    const Vec3 radial = q > 0 ? Vec3{p[0] / q, 0, p[2] / q} : Vec3{1, 0, 0};
    const Vec3 c = mul(radial, t.major_radius);
    const Vec3 w = sub(p, c);
    const double l = norm(w);
    SurfacePoint r;
    r.normal = l > 0 ? mul(w, 1.0 / l) : radial;
    r.point = add(c, mul(r.normal, t.minor_radius));
    r.signed_distance = l - t.minor_radius;
    return r;
}

SurfacePoint closest(const Cube& c, const Vec3& p) {
    const double h = 0.5 * c.edge;
    return closest_box({h, h, h}, p);
}

SurfacePoint closest(const Plane& s, const Vec3& p) {
    const double h = 0.5 * s.size;
    SurfacePoint r;
    r.point = {std::clamp(p[0], -h, h), 0.0, std::clamp(p[2], -h, h)};
    r.normal = {0, 1, 0};
    const double d = norm(sub(p, r.point));
    r.signed_distance = p[1] < 0 ? -d : d;
    return r;
}

SurfacePoint closest(const Room& room, const Vec3& p) {
    // Walls: the inside of the box seen from within: distance to the box surface, normal inward.
    const double h = 0.5 * room.size;
    SurfacePoint walls = closest_box({h, h, h}, p);
    walls.signed_distance = -walls.signed_distance;
    walls.normal = mul(walls.normal, -1.0);
    static constexpr int k_face_part[6] = {k_room_right_wall, k_room_left_wall,  k_room_ceiling,
                                           k_room_floor,      k_room_front_wall, k_room_back_wall};
    walls.part = k_face_part[walls.part];

    SurfacePoint sphere = closest(Sphere{room.sphere_radius}, sub(p, room.sphere_center));
    sphere.point = add(sphere.point, room.sphere_center);
    sphere.part = k_room_sphere;

    const double yaw = room.cube_yaw_degrees * k_pi / 180.0;
    SurfacePoint cube = closest(Cube{room.cube_edge}, rotate_y(sub(p, room.cube_center), -yaw));
    cube.point = add(rotate_y(cube.point, yaw), room.cube_center);
    cube.normal = rotate_y(cube.normal, yaw);
    cube.part = k_room_cube;

    // Each part's value is its exact signed distance, so the distance to the union of the part
    // surfaces is the smallest magnitude; the air is where all three are positive.
    SurfacePoint best = walls;
    for (const SurfacePoint* c : {&sphere, &cube})
        if (std::fabs(c->signed_distance) < std::fabs(best.signed_distance)) best = *c;
    const bool in_air = std::min({walls.signed_distance, sphere.signed_distance, cube.signed_distance}) >= 0;
    best.signed_distance = in_air ? std::fabs(best.signed_distance) : -std::fabs(best.signed_distance);
    return best;
}

SurfacePoint closest(const Ring& ring, const Vec3& p) {
    // In the (rho, y) half-plane the band is the rectangle [r, r + t] x [-h/2, h/2]: the nearest
    // point of the solid's surface is the nearest point of that rectangle's boundary, turned back
    // about the axis.
    const double rho = std::hypot(p[0], p[2]);
    const Vec3 radial = rho > 0 ? Vec3{p[0] / rho, 0, p[2] / rho} : Vec3{1, 0, 0};
    const double mid = ring.radius + 0.5 * ring.thickness;
    const SurfacePoint b = closest_box({0.5 * ring.thickness, 0.5 * ring.height, 1.0}, {rho - mid, p[1], 0.0});
    SurfacePoint r;
    const double rho_s = mid + b.point[0];
    r.point = {radial[0] * rho_s, b.point[1], radial[2] * rho_s};
    r.normal = {radial[0] * b.normal[0], b.normal[1], radial[2] * b.normal[0]};
    r.signed_distance = b.signed_distance;
    r.part = b.part == 1 ? k_ring_inner : b.part == 0 ? k_ring_outer : b.part == 2 ? k_ring_top : k_ring_part_count;
    return r;
}

SurfacePoint closest(const Shape& shape, const Vec3& world_point) {
    const Vec3 p = mul(sub(world_point, shape.offset), 1.0 / shape.scale);
    SurfacePoint r;
    switch (shape.kind) {
        case ShapeKind::sphere:
            r = closest(shape.sphere, p);
            break;
        case ShapeKind::torus:
            r = closest(shape.torus, p);
            break;
        case ShapeKind::cube:
            r = closest(shape.cube, p);
            break;
        case ShapeKind::plane:
            r = closest(shape.plane, p);
            break;
        case ShapeKind::room:
            r = closest(shape.room, p);
            break;
        case ShapeKind::ring:
            r = closest(shape.ring, p);
            break;
    }
    r.point = add(mul(r.point, shape.scale), shape.offset);
    r.signed_distance *= shape.scale;
    return r;
}

double surface_area(const Shape& shape) {
    double a = 0;
    switch (shape.kind) {
        case ShapeKind::sphere:
            a = 4 * k_pi * shape.sphere.radius * shape.sphere.radius;
            break;
        case ShapeKind::torus:
            a = 4 * k_pi * k_pi * shape.torus.major_radius * shape.torus.minor_radius;
            break;
        case ShapeKind::cube:
            a = 6 * shape.cube.edge * shape.cube.edge;
            break;
        case ShapeKind::plane:
            a = shape.plane.size * shape.plane.size;
            break;
        case ShapeKind::room: {
            const Room& r = shape.room;
            a = 6 * r.size * r.size + 4 * k_pi * r.sphere_radius * r.sphere_radius +
                5 * r.cube_edge * r.cube_edge;
            break;
        }
        case ShapeKind::ring: {
            const Ring& r = shape.ring;
            const double o = r.radius + r.thickness;
            a = 2 * k_pi * (r.radius + o) * r.height + k_pi * (o * o - r.radius * r.radius);
            break;
        }
    }
    return a * shape.scale * shape.scale;
}

std::array<Vec3, 2> shape_bounds(const Shape& shape) {
    Vec3 h{};
    switch (shape.kind) {
        case ShapeKind::sphere:
            h = {shape.sphere.radius, shape.sphere.radius, shape.sphere.radius};
            break;
        case ShapeKind::torus: {
            const double o = shape.torus.major_radius + shape.torus.minor_radius;
            h = {o, shape.torus.minor_radius, o};
            break;
        }
        case ShapeKind::cube:
            h = {0.5 * shape.cube.edge, 0.5 * shape.cube.edge, 0.5 * shape.cube.edge};
            break;
        case ShapeKind::plane:
            h = {0.5 * shape.plane.size, 0.0, 0.5 * shape.plane.size};
            break;
        case ShapeKind::room:
            h = {0.5 * shape.room.size, 0.5 * shape.room.size, 0.5 * shape.room.size};
            break;
        case ShapeKind::ring: {
            const double o = shape.ring.radius + shape.ring.thickness;
            h = {o, 0.5 * shape.ring.height, o};
            break;
        }
    }
    return {add(mul(h, -shape.scale), shape.offset), add(mul(h, shape.scale), shape.offset)};
}

double shape_size(const Shape& shape) {
    const auto b = shape_bounds(shape);
    return std::max({b[1][0] - b[0][0], b[1][1] - b[0][1], b[1][2] - b[0][2]});
}

// ---- JSON ---------------------------------------------------------------------------------------

std::string shape_to_json(const Shape& s) {
    nlohmann::ordered_json j;
    j["kind"] = shape_name(s.kind);
    switch (s.kind) {
        case ShapeKind::sphere:
            j["radius"] = s.sphere.radius;
            break;
        case ShapeKind::torus:
            j["major_radius"] = s.torus.major_radius;
            j["minor_radius"] = s.torus.minor_radius;
            j["axis"] = "y";
            break;
        case ShapeKind::cube:
            j["edge"] = s.cube.edge;
            break;
        case ShapeKind::plane:
            j["size"] = s.plane.size;
            j["normal"] = "+y";
            break;
        case ShapeKind::room:
            j["size"] = s.room.size;
            j["sphere_center"] = s.room.sphere_center;
            j["sphere_radius"] = s.room.sphere_radius;
            j["cube_center"] = s.room.cube_center;
            j["cube_edge"] = s.room.cube_edge;
            j["cube_yaw_degrees"] = s.room.cube_yaw_degrees;
            break;
        case ShapeKind::ring:
            j["radius"] = s.ring.radius;
            j["thickness"] = s.ring.thickness;
            j["height"] = s.ring.height;
            j["axis"] = "y";
            break;
    }
    j["scale"] = s.scale;
    j["offset"] = s.offset;
    return j.dump();
}

namespace {

Shape shape_from(const nlohmann::json& j, const std::string& label) {
    auto fail = [&](const std::string& what) -> void { throw Error(label + ": synthetic shape: " + what); };
    if (!j.is_object()) fail("expected a JSON object");
    auto number = [&](const char* key) {
        auto it = j.find(key);
        if (it == j.end() || !it->is_number()) fail(std::string("missing number \"") + key + "\"");
        return it->get<double>();
    };
    auto vec = [&](const char* key) {
        auto it = j.find(key);
        if (it == j.end() || !it->is_array() || it->size() != 3 || !(*it)[0].is_number() ||
            !(*it)[1].is_number() || !(*it)[2].is_number())
            fail(std::string("missing [x, y, z] \"") + key + "\"");
        return Vec3{(*it)[0].get<double>(), (*it)[1].get<double>(), (*it)[2].get<double>()};
    };
    auto kind = j.find("kind");
    if (kind == j.end() || !kind->is_string()) fail("missing string \"kind\"");
    Shape s;
    try {
        s.kind = shape_kind(kind->get<std::string>());
    } catch (const Error& e) {
        fail(e.what());
    }
    switch (s.kind) {
        case ShapeKind::sphere:
            s.sphere.radius = number("radius");
            break;
        case ShapeKind::torus:
            s.torus.major_radius = number("major_radius");
            s.torus.minor_radius = number("minor_radius");
            break;
        case ShapeKind::cube:
            s.cube.edge = number("edge");
            break;
        case ShapeKind::plane:
            s.plane.size = number("size");
            break;
        case ShapeKind::room:
            s.room.size = number("size");
            s.room.sphere_center = vec("sphere_center");
            s.room.sphere_radius = number("sphere_radius");
            s.room.cube_center = vec("cube_center");
            s.room.cube_edge = number("cube_edge");
            s.room.cube_yaw_degrees = number("cube_yaw_degrees");
            break;
        case ShapeKind::ring:
            s.ring.radius = number("radius");
            s.ring.thickness = number("thickness");
            s.ring.height = number("height");
            break;
    }
    s.scale = number("scale");
    s.offset = vec("offset");
    try {
        validate(s);
    } catch (const Error& e) {
        fail(e.what());
    }
    return s;
}

}  // namespace

Shape shape_from_json(const std::string& json_text, const std::string& label) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(json_text);
    } catch (const nlohmann::json::exception& e) {
        throw Error(label + ": synthetic shape: invalid JSON: " + e.what());
    }
    return shape_from(j, label);
}

Shape shape_from_provenance(const std::string& provenance_json, const std::string& label) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(provenance_json);
    } catch (const nlohmann::json::exception& e) {
        throw Error(label + ": provenance: invalid JSON: " + e.what());
    }
    if (!j.is_array()) throw Error(label + ": provenance: expected a JSON array");
    for (auto it = j.rbegin(); it != j.rend(); ++it) {
        if (!it->is_object()) continue;
        auto tool = it->find("tool");
        if (tool == it->end() || !tool->is_string() || tool->get<std::string>() != "prt-synth") continue;
        auto params = it->find("parameters");
        if (params == it->end() || !params->is_object() || !params->contains("shape"))
            throw Error(label + ": provenance: the prt-synth entry has no \"parameters\".\"shape\"");
        return shape_from((*params)["shape"], label);
    }
    throw Error(label + ": not a synthetic model (no prt-synth entry in its provenance)");
}

}  // namespace prt::synth
