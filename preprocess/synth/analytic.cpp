#include "analytic.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <utility>

#include "prt/error.h"

namespace prt::synth {
namespace {

constexpr double k_pi = 3.14159265358979323846;

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
    for (ShapeKind k : {ShapeKind::sphere, ShapeKind::torus, ShapeKind::cube, ShapeKind::plane,
                        ShapeKind::room, ShapeKind::ring})
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
    const double d = length(p);
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
    const double l = length(w);
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
    const double d = length(sub(p, r.point));
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
    const SurfacePoint b =
        closest_box({0.5 * ring.thickness, 0.5 * ring.height, 1.0}, {rho - mid, p[1], 0.0});
    SurfacePoint r;
    const double rho_s = mid + b.point[0];
    r.point = {radial[0] * rho_s, b.point[1], radial[2] * rho_s};
    r.normal = {radial[0] * b.normal[0], b.normal[1], radial[2] * b.normal[0]};
    r.signed_distance = b.signed_distance;
    r.part = b.part == 1   ? k_ring_inner
             : b.part == 0 ? k_ring_outer
             : b.part == 2 ? k_ring_top
                           : k_ring_part_count;
    return r;
}

SurfacePoint closest(const Shape& shape, const Vec3& world_point) {
    const Vec3 p = mul(sub(world_point, shape.offset), 1.0 / shape.scale);
    SurfacePoint r = visit_shape(shape, [&p](const auto& s) { return closest(s, p); });
    r.point = add(mul(r.point, shape.scale), shape.offset);
    r.signed_distance *= shape.scale;
    return r;
}

// ---- Ray casting ---------------------------------------------------------------------------------

namespace {

constexpr double k_inf = std::numeric_limits<double>::infinity();

/// A first hit in a shape's own frame (scale 1, no offset); t along the unit direction.
struct LocalHit {
    double t = 0;
    Vec3 point{};
    Vec3 normal{};
    int part = 0;
};
using MaybeHit = std::optional<LocalHit>;

/// The roots b -+ s of a quadratic whose roots multiply to c (in order up to rounding): the one of
/// larger magnitude from b + sign(b) s, the other as c over it, so neither loses digits to
/// cancellation (Haines et al., Ray Tracing Gems 2019, ch. 7).
void stable_roots(double b, double s, double c, double& t0, double& t1) {
    if (b > 0) {
        t1 = b + s;
        t0 = c / t1;
    } else if (b < 0) {
        t0 = b - s;
        t1 = c / t0;
    } else {
        t0 = -s;
        t1 = s;
    }
}

/// Both roots t0 <= t1 of |f + t u|^2 = r^2 for the unit direction u and the offset f of the ray
/// origin from the centre, or false. Haines et al. (Ray Tracing Gems 2019, ch. 7): the discriminant
/// from the perpendicular offset at closest approach, and the smaller root from the product of the
/// roots, so neither a distant origin nor an origin near the surface loses digits.
bool sphere_roots(const Vec3& f, const Vec3& u, double r, double& t0, double& t1) {
    const double b = -dot(f, u);  // closest approach
    const double q = length(add(f, mul(u, b)));
    const double disc = (r - q) * (r + q);
    if (!(disc >= 0)) return false;
    const double s = std::sqrt(disc);
    const double fl = length(f);
    const double c = (fl - r) * (fl + r);  // t0 t1
    stable_roots(b, s, c, t0, t1);
    if (t0 > t1) std::swap(t0, t1);
    return true;
}

/// The first root in [0, t_max] of a pair t0 <= t1 (entry, exit of a convex solid), with which.
bool first_root(double t0, double t1, double t_max, double& t, bool& exiting) {
    if (t0 >= 0) {
        t = t0;
        exiting = false;
    } else if (t1 >= 0) {
        t = t1;
        exiting = true;
    } else {
        return false;
    }
    return t <= t_max;
}

MaybeHit sphere_hit(const Vec3& center, double r, const Vec3& o, const Vec3& u, double t_max) {
    double t0, t1, t;
    bool exiting;
    if (!sphere_roots(sub(o, center), u, r, t0, t1) || !first_root(t0, t1, t_max, t, exiting)) return {};
    LocalHit h;
    h.t = t;
    const Vec3 w = sub(add(o, mul(u, t)), center);
    const double l = length(w);
    h.normal = l > 0 ? mul(w, 1.0 / l) : Vec3{0, 1, 0};
    h.point = add(center, mul(h.normal, r));  // on the sphere to rounding
    return h;
}

/// Slabs (Kay and Kajiya 1986): entry and exit of the line o + t u (all t) with the box [-h, h],
/// and the axis of each; false when the line misses the box.
bool box_roots(const Vec3& half, const Vec3& o, const Vec3& u, double& t0, int& a0, double& t1, int& a1) {
    t0 = -k_inf;
    t1 = k_inf;
    a0 = a1 = 0;
    for (int a = 0; a < 3; ++a) {
        if (u[a] == 0) {
            if (std::fabs(o[a]) > half[a]) return false;
            continue;
        }
        double ta = (-half[a] - o[a]) / u[a], tb = (half[a] - o[a]) / u[a];
        if (ta > tb) std::swap(ta, tb);
        if (ta > t0) t0 = ta, a0 = a;
        if (tb < t1) t1 = tb, a1 = a;
    }
    return t0 <= t1;
}

/// First crossing of the box [-h, h]'s surface; part = face 2 axis + (negative side), normal outward.
MaybeHit box_hit(const Vec3& half, const Vec3& o, const Vec3& u, double t_max) {
    double t0, t1, t;
    int a0, a1;
    bool exiting;
    if (!box_roots(half, o, u, t0, a0, t1, a1) || !first_root(t0, t1, t_max, t, exiting)) return {};
    const int axis = exiting ? a1 : a0;
    // Entering through the face the ray faces; leaving through the one it moves towards.
    const double side = (u[axis] > 0) == exiting ? 1.0 : -1.0;
    LocalHit h;
    h.t = t;
    for (int a = 0; a < 3; ++a) h.point[a] = std::clamp(o[a] + t * u[a], -half[a], half[a]);
    h.point[axis] = side * half[axis];
    h.normal = {0, 0, 0};
    h.normal[axis] = side;
    h.part = 2 * axis + (side < 0 ? 1 : 0);
    return h;
}

MaybeHit local_hit(const Plane& s, const Vec3& o, const Vec3& u, double t_max) {
    if (u[1] == 0) return {};  // in or parallel to the plane: grazing, no crossing
    const double t = -o[1] / u[1];
    if (!(t >= 0 && t <= t_max)) return {};
    const double h = 0.5 * s.size;
    LocalHit r;
    r.t = t;
    r.point = {o[0] + t * u[0], 0.0, o[2] + t * u[2]};
    if (std::fabs(r.point[0]) > h || std::fabs(r.point[2]) > h) return {};
    r.normal = {0, 1, 0};
    return r;
}

MaybeHit local_hit(const Room& room, const Vec3& o, const Vec3& u, double t_max) {
    const double hs = 0.5 * room.size;
    MaybeHit best = box_hit({hs, hs, hs}, o, u, t_max);
    if (best) {  // the walls: the box's faces with normals into the room
        static constexpr int k_face_part[6] = {k_room_right_wall, k_room_left_wall,  k_room_ceiling,
                                               k_room_floor,      k_room_front_wall, k_room_back_wall};
        best->part = k_face_part[best->part];
        best->normal = mul(best->normal, -1.0);
    }
    if (MaybeHit s = sphere_hit(room.sphere_center, room.sphere_radius, o, u, t_max);
        s && (!best || s->t < best->t)) {
        s->part = k_room_sphere;
        best = s;
    }
    const double yaw = room.cube_yaw_degrees * k_pi / 180.0;
    const double he = 0.5 * room.cube_edge;
    if (MaybeHit c =
            box_hit({he, he, he}, rotate_y(sub(o, room.cube_center), -yaw), rotate_y(u, -yaw), t_max);
        c && (!best || c->t < best->t)) {
        c->point = add(rotate_y(c->point, yaw), room.cube_center);
        c->normal = rotate_y(c->normal, yaw);
        c->part = k_room_cube;
        best = c;
    }
    return best;
}

/// A closed interval of the ray parameter with what bounds it at each end (RingPart, or
/// k_ring_part_count for the bottom).
struct Span {
    double lo = -k_inf, hi = k_inf;
    int lo_part = 0, hi_part = 0;
};

/// Where the line o + t u (u unit) is within distance `radius` of the y axis: false if nowhere,
/// `span` the whole line when the line is parallel to the axis and inside.
bool cylinder_span(double radius, const Vec3& o, const Vec3& u, int part, Span& span) {
    const double a = u[0] * u[0] + u[2] * u[2];
    const double wl = std::hypot(o[0], o[2]);
    span = Span{-k_inf, k_inf, part, part};
    if (a == 0) return wl <= radius;
    // The 2D closest-approach quadratic (as sphere_roots), direction (u_x, u_z) of length sqrt(a).
    const double b = -(o[0] * u[0] + o[2] * u[2]) / a;
    const double q = std::hypot(o[0] + b * u[0], o[2] + b * u[2]);
    const double disc = (radius - q) * (radius + q) / a;
    if (!(disc >= 0)) return false;
    const double s = std::sqrt(disc);
    const double c = (wl - radius) * (wl + radius) / a;
    double t0, t1;
    stable_roots(b, s, c, t0, t1);
    span.lo = std::min(t0, t1);
    span.hi = std::max(t0, t1);
    return true;
}

/// The ring as a solid: (inside the outer cylinder and the slab |y| <= h/2) minus the open inside
/// of the inner cylinder; its boundary points along the ray in order, the first one >= 0 wins.
MaybeHit local_hit(const Ring& ring, const Vec3& o, const Vec3& u, double t_max) {
    const double hh = 0.5 * ring.height, outer = ring.radius + ring.thickness;
    Span band;
    if (!cylinder_span(outer, o, u, k_ring_outer, band)) return {};
    if (u[1] == 0) {
        if (std::fabs(o[1]) > hh) return {};
    } else {
        double ta = (-hh - o[1]) / u[1], tb = (hh - o[1]) / u[1];
        int pa = k_ring_part_count, pb = k_ring_top;  // y = -h/2 (bottom), y = +h/2 (top)
        if (ta > tb) std::swap(ta, tb), std::swap(pa, pb);
        if (ta > band.lo) band.lo = ta, band.lo_part = pa;
        if (tb < band.hi) band.hi = tb, band.hi_part = pb;
    }
    if (band.lo > band.hi) return {};
    std::array<std::pair<double, int>, 4> ends;
    int n = 0;
    Span hole;
    if (!cylinder_span(ring.radius, o, u, k_ring_inner, hole)) {
        ends[n++] = {band.lo, band.lo_part};
        ends[n++] = {band.hi, band.hi_part};
    } else {
        if (hole.lo == -k_inf && hole.hi == k_inf) return {};  // along the axis, inside the hole
        if (band.lo <= std::min(band.hi, hole.lo)) {
            ends[n++] = {band.lo, band.lo_part};
            ends[n++] =
                hole.lo < band.hi ? std::pair{hole.lo, int(k_ring_inner)} : std::pair{band.hi, band.hi_part};
        }
        if (std::max(band.lo, hole.hi) <= band.hi) {
            ends[n++] =
                hole.hi > band.lo ? std::pair{hole.hi, int(k_ring_inner)} : std::pair{band.lo, band.lo_part};
            ends[n++] = {band.hi, band.hi_part};
        }
    }
    for (int i = 0; i < n; ++i) {
        const auto [t, part] = ends[i];
        if (t < 0) continue;
        if (t > t_max) return {};
        LocalHit h;
        h.t = t;
        h.part = part;
        Vec3 p = add(o, mul(u, t));
        const double rho = std::hypot(p[0], p[2]);
        const Vec3 radial = rho > 0 ? Vec3{p[0] / rho, 0, p[2] / rho} : Vec3{1, 0, 0};
        if (part == k_ring_outer || part == k_ring_inner) {
            const double r = part == k_ring_outer ? outer : ring.radius;
            p = {radial[0] * r, std::clamp(p[1], -hh, hh), radial[2] * r};
            h.normal = part == k_ring_outer ? radial : mul(radial, -1.0);
        } else {
            const double r = std::clamp(rho, ring.radius, outer);
            p = {radial[0] * r, part == k_ring_top ? hh : -hh, radial[2] * r};
            h.normal = {0, part == k_ring_top ? 1.0 : -1.0, 0};
        }
        h.point = p;
        return h;
    }
    return {};
}

/// Bisects [a, b] (f(a), f(b) of opposite signs, or one zero) down to adjacent doubles; returns
/// the end with the smaller |f|.
template <class F>
double bisect(const F& f, double a, double b) {
    double fa = f(a), fb = f(b);
    if (fa == 0) return a;
    if (fb == 0) return b;
    for (int i = 0; i < 2200; ++i) {  // ~64 halvings reach adjacent doubles; the bound is a guard
        const double m = 0.5 * (a + b);
        if (!(m > a && m < b)) break;
        const double fm = f(m);
        if (fm == 0) return m;
        if ((fm < 0) == (fa < 0))
            a = m, fa = fm;
        else
            b = m, fb = fm;
    }
    return std::fabs(fa) <= std::fabs(fb) ? a : b;
}

/// The torus: its points satisfy the quartic f(x) = (|p|^2 + R^2 - r^2)^2 - 4 R^2 (p_x^2 + p_z^2) = 0
/// along the ray, and f has the sign of the exact signed distance, (|p|^2 + R^2 - r^2 - 2 R rho)
/// being (rho - R)^2 + y^2 - r^2 and the other factor positive for r < R. Between consecutive
/// critical points f is monotone, so each piece holds at most one root, present exactly when the
/// signed distance differs in sign at its ends: the first such piece is bisected on the signed
/// distance itself (exact to rounding; the polynomial only places the pieces). The critical points
/// (roots of the cubic f') come the same way from the roots of the quadratic f''.
MaybeHit local_hit(const Torus& tor, const Vec3& o, const Vec3& u, double t_max) {
    const double R = tor.major_radius, r = tor.minor_radius;
    double s0, s1;
    if (!sphere_roots(o, u, R + r, s0, s1) || s1 < 0) return {};  // the bounding sphere
    const double base = std::max(s0, 0.0);
    const double length = std::min(s1, t_max) - base;
    if (!(length >= 0)) return {};
    const Vec3 p = add(o, mul(u, base));  // shifted origin: coefficients of size (R + r)^4 at most
    const double uu = dot(u, u), b = dot(p, u), c = dot(p, p) + (R - r) * (R + r);
    const double e = u[0] * u[0] + u[2] * u[2], g = p[0] * u[0] + p[2] * u[2];
    const double r4 = 4 * R * R;
    // f = k4 x^4 + k3 x^3 + k2 x^2 + k1 x + k0; only f' and f'' are evaluated (f's sign is sd's).
    const double k4 = uu * uu, k3 = 4 * uu * b, k2 = 4 * b * b + 2 * uu * c - r4 * e,
                 k1 = 4 * b * c - 2 * r4 * g;
    auto d1 = [&](double x) { return ((4 * k4 * x + 3 * k3) * x + 2 * k2) * x + k1; };
    auto sd = [&](double x) {
        const Vec3 q = add(p, mul(u, x));
        return std::hypot(std::hypot(q[0], q[2]) - R, q[1]) - r;
    };
    // Roots of f'' = 12 k4 x^2 + 6 k3 x + 2 k2 in (0, length): the pieces where f' is monotone.
    std::array<double, 4> cuts{};
    int nc = 0;
    cuts[nc++] = 0;
    {
        const double qa = 12 * k4, qb = 6 * k3, qc = 2 * k2;
        const double disc = qb * qb - 4 * qa * qc;
        if (disc >= 0) {
            const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
            double x0 = q / qa, x1 = q != 0 ? qc / q : x0;
            if (x0 > x1) std::swap(x0, x1);
            for (double x : {x0, x1})
                if (x > cuts[nc - 1] && x < length) cuts[nc++] = x;
        }
    }
    cuts[nc++] = length;
    // Roots of f' in (0, length): the pieces where f is monotone.
    std::array<double, 5> pieces{};
    int np = 0;
    pieces[np++] = 0;
    for (int i = 0; i + 1 < nc; ++i) {
        const double a = cuts[i], z = cuts[i + 1], fa = d1(a), fz = d1(z);
        if ((fa < 0 && fz > 0) || (fa > 0 && fz < 0)) {
            const double x = bisect(d1, a, z);
            if (x > pieces[np - 1] && x < length) pieces[np++] = x;
        }
    }
    pieces[np++] = length;
    double prev = sd(0);
    for (int i = 0; i < np; ++i) {
        const double x = pieces[i];
        const double cur = i == 0 ? prev : sd(x);
        double root = -1;
        if (cur == 0)
            root = x;
        else if (i > 0 && (cur < 0) != (prev < 0))
            root = bisect(sd, pieces[i - 1], x);
        if (root >= 0) {
            LocalHit hit;
            hit.t = base + root;
            const SurfacePoint sp = closest(tor, add(p, mul(u, root)));
            hit.point = sp.point;
            hit.normal = sp.normal;
            return hit;
        }
        prev = cur;
    }
    return {};
}

MaybeHit local_hit(const Sphere& s, const Vec3& o, const Vec3& u, double t_max) {
    return sphere_hit({0, 0, 0}, s.radius, o, u, t_max);
}
MaybeHit local_hit(const Cube& c, const Vec3& o, const Vec3& u, double t_max) {
    const double e = 0.5 * c.edge;
    return box_hit({e, e, e}, o, u, t_max);
}

}  // namespace

std::optional<RayHit> first_hit(const Shape& shape, const Vec3& origin, const Vec3& dir, double t_max) {
    const double len = length(dir);
    if (!(len > 0) || !std::isfinite(len) || !std::isfinite(length(origin)))
        throw Error("first_hit: the ray origin and direction must be finite, the direction non-zero");
    if (!(t_max >= 0)) return std::nullopt;
    const Vec3 o = mul(sub(origin, shape.offset), 1.0 / shape.scale);
    const Vec3 u = mul(dir, 1.0 / len);
    const double local_max = t_max * len / shape.scale;  // +inf stays +inf
    const MaybeHit h = visit_shape(shape, [&](const auto& s) { return local_hit(s, o, u, local_max); });
    if (!h) return std::nullopt;
    RayHit r;
    r.t = std::min(h->t * shape.scale / len, t_max);
    r.point = add(mul(h->point, shape.scale), shape.offset);
    r.normal = h->normal;
    r.part = h->part;
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
