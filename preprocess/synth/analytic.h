// PointRT synthetic models: the analytic shapes prt-synth samples, with their exact ground truth
// (signed distance, closest point, true normal). Benchmarks measure hit-point and normal errors of
// every surface representation (splats, ISO, MLS) against these, and rebuild the shape of a pool
// from its provenance (shape_from_provenance), so a number in a table can always be recomputed.
//
// Conventions (all shapes in their own frame, then Shape::scale and Shape::offset):
//   y is up; every shape is centred at the origin of its frame.
//   sphere  radius r
//   torus   major radius R (centre circle in the xz-plane), minor radius r < R (tube), axis y
//   cube    edge e, axis-aligned, faces at +-e/2
//   plane   square of side s in the plane y = 0 (|x|, |z| <= s/2), normal +y
//   room    closed box [-s/2, s/2]^3 seen from inside (normals point into the room), with a sphere
//           resting on the floor and a cube resting on the floor turned about y (normals outward)
//   ring    a cylindrical band about the y axis: inner radius r, wall thickness t, height h
//           (|y| <= h/2); its inner wall (normals towards the axis), outer wall (outward) and top rim
//           (+y) are sampled, not its bottom (it stands on a floor): a mirror band for caustics
//
// Signed distances are positive on the side the normals point to: outside the sphere, torus and
// cube, above the plane (y >= 0), and in the room's air (inside the walls, outside both objects).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "prt/formats/pool_layout.h"
#include "prt/vec3.h"

namespace prt::synth {

using Vec3 = Vec3d;

/// Rotation about +y by `radians` (right-handed: +z turns towards +x).
inline Vec3 rotate_y(const Vec3& v, double radians) {
    const double c = std::cos(radians), s = std::sin(radians);
    return {c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]};
}

enum class ShapeKind : std::uint32_t { sphere, torus, cube, plane, room, ring };

/// "sphere", "torus", "cube", "plane", "room", "ring".
const char* shape_name(ShapeKind kind);
/// The kind named `name`; throws prt::Error for an unknown name.
ShapeKind shape_kind(const std::string& name);

struct Sphere {
    double radius = 1.0;
};

struct Torus {
    double major_radius = 1.0;   ///< R: radius of the tube's centre circle
    double minor_radius = 0.25;  ///< r: tube radius, 0 < r < R (a ring torus)
};

struct Cube {
    double edge = 2.0;
};

struct Plane {
    double size = 2.0;  ///< side of the square
};
/// A cylindrical band (thesis Fig. 5.3a: the reflective ring of the cardioid caustic).
struct Ring {
    double radius = 1.0;      ///< inner radius r
    double thickness = 0.02;  ///< wall thickness t: outer radius r + t
    double height = 0.4;      ///< h: the band spans |y| <= h/2
};
/// Parts of the ring, in the order prt-synth writes them.
enum RingPart : int { k_ring_inner = 0, k_ring_outer = 1, k_ring_top = 2, k_ring_part_count = 3 };

/// A Cornell-box-like room. The geometry of the two objects is stored explicitly (not derived from
/// `size` when read back), so a pool's provenance rebuilds exactly the shape that was sampled.
struct Room {
    double size = 2.0;  ///< inner edge of the box [-size/2, size/2]^3
    Vec3 sphere_center{-0.4, -0.6, -0.2};
    double sphere_radius = 0.4;
    Vec3 cube_center{0.44, -0.7, 0.24};
    double cube_edge = 0.6;
    double cube_yaw_degrees = 25.0;  ///< rotation of the cube about +y (right-handed)

    /// The standard layout for a room of side `size`: a sphere of radius 0.2 size and a cube of
    /// edge 0.3 size, both resting on the floor, apart from each other and from the walls.
    static Room standard(double size);
};

/// Parts of the room, in the order prt-synth writes them (points of a part are contiguous).
enum RoomPart : int {
    k_room_floor = 0,       ///< y = -size/2, normal +y
    k_room_ceiling = 1,     ///< y = +size/2, normal -y
    k_room_left_wall = 2,   ///< x = -size/2, normal +x (red)
    k_room_right_wall = 3,  ///< x = +size/2, normal -x (green)
    k_room_back_wall = 4,   ///< z = -size/2, normal +z
    k_room_front_wall = 5,  ///< z = +size/2, normal -z (behind a camera looking down -z)
    k_room_sphere = 6,      ///< normals outward
    k_room_cube = 7,        ///< normals outward; its bottom face lies on the floor and is not sampled
    k_room_part_count = 8,
};
/// Name of a room part ("floor", "ceiling", "left_wall", ...).
const char* room_part_name(int part);
/// The color prt-synth gives a room part: all eight differ, so a point's color names its part.
pool::Rgba8 room_part_color(int part);
/// The part whose color is `c` (alpha ignored), or -1.
int room_part_from_color(pool::Rgba8 c);

/// Cube faces as parts: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z.
const char* cube_face_name(int face);
pool::Rgba8 cube_face_color(int face);

/// An analytic shape placed in the world: world = local * scale + offset (normals unchanged).
struct Shape {
    ShapeKind kind = ShapeKind::sphere;
    Sphere sphere;
    Torus torus;
    Cube cube;
    Plane plane;
    Room room;
    Ring ring;
    double scale = 1.0;
    Vec3 offset{0, 0, 0};
};

/// `f(parameters)` for the parameters of the shape's kind (shape.sphere, shape.torus, ...): one
/// dispatch for the per-shape overloads (closest, ray hits) instead of a switch in each.
template <class F>
decltype(auto) visit_shape(const Shape& shape, F&& f) {
    switch (shape.kind) {
        case ShapeKind::sphere:
            break;
        case ShapeKind::torus:
            return f(shape.torus);
        case ShapeKind::cube:
            return f(shape.cube);
        case ShapeKind::plane:
            return f(shape.plane);
        case ShapeKind::room:
            return f(shape.room);
        case ShapeKind::ring:
            return f(shape.ring);
    }
    return f(shape.sphere);
}

/// Throws prt::Error ("what: value") when a parameter is not finite or out of range: radii, edges
/// and sizes > 0, minor < major radius, scale > 0, the room's objects inside the room.
void validate(const Shape& shape);

/// The exact answer to "where is the surface nearest to p" (world frame).
struct SurfacePoint {
    Vec3 point{};                ///< closest point on the surface
    Vec3 normal{};               ///< true unit normal of the surface at `point` (see each shape)
    double signed_distance = 0;  ///< |p - point|, positive on the side the normal points to
    int part = 0;                ///< room part, cube face, or 0
};

// Per-shape queries in the shape's own frame (scale 1, no offset).
SurfacePoint closest(const Sphere& s, const Vec3& p);
SurfacePoint closest(const Torus& t, const Vec3& p);
/// Normal: the face normal of the axis where p is farthest out (|p_a| - e/2 largest), so a point on
/// an edge or corner gets the normal of one of its faces.
SurfacePoint closest(const Cube& c, const Vec3& p);
/// The square only (not the infinite plane); normal +y everywhere; sign from the side of y = 0.
SurfacePoint closest(const Plane& s, const Vec3& p);
/// The nearest of walls, sphere and cube; sign: + in the air, - inside the walls or an object.
SurfacePoint closest(const Room& r, const Vec3& p);
/// The band as a solid annulus r <= rho <= r + t, |y| <= h/2 (its unsampled bottom included);
/// sign + outside it; part: k_ring_inner, k_ring_outer, k_ring_top (bottom: k_ring_part_count).
SurfacePoint closest(const Ring& r, const Vec3& p);

/// World-frame query of a placed shape.
SurfacePoint closest(const Shape& shape, const Vec3& world_point);
inline double signed_distance(const Shape& shape, const Vec3& p) {
    return closest(shape, p).signed_distance;
}
inline Vec3 closest_point(const Shape& shape, const Vec3& p) {
    return closest(shape, p).point;
}
inline Vec3 true_normal(const Shape& shape, const Vec3& p) {
    return closest(shape, p).normal;
}

/// The first point where a ray meets a shape's surface (first_hit).
struct RayHit {
    double t = 0;   ///< ray parameter: point = origin + t dir, 0 <= t <= t_max
    Vec3 point{};   ///< world frame, on the surface (to rounding)
    Vec3 normal{};  ///< true unit normal there, as closest() orients it (it may face away from the ray)
    int part = 0;   ///< as SurfacePoint::part: room part, cube face, ring part, or 0
};

/// The first point of the shape's surface on the ray origin + t dir, 0 <= t <= t_max (world frame;
/// dir non-zero, not necessarily unit: t is in units of |dir|). The surface is that of closest():
/// solids' boundaries (a ray starting inside a solid hits its exit), the plane's square from either
/// side, the room's walls seen from inside or outside and its objects, the ring's whole band
/// (its unsampled bottom: part k_ring_part_count). Exact in double, in the shape's own frame:
/// sphere by the closest-approach quadratic (Haines et al., "Precision Improvements for Ray/Sphere
/// Intersection", Ray Tracing Gems 2019, ch. 7), boxes (cube, room walls, the room's turned cube in
/// its frame) by slabs (Kay and Kajiya 1986), the plane directly, the ring as the intersection of
/// two cylinders' and a slab's intervals; the torus by isolating the roots of its quartic between
/// the critical points of the quartic (found the same way from its cubic derivative), then bisecting
/// the exact signed distance to machine precision. Grazing rays resolve to rounding: a ray that
/// touches a surface within ~1e-15 of the size may count as a hit or a miss. Returns nothing on a
/// miss.
std::optional<RayHit> first_hit(const Shape& shape, const Vec3& origin, const Vec3& dir,
                                double t_max = std::numeric_limits<double>::infinity());

/// Area of the sampled surface, world units (the room without the cube's bottom face).
double surface_area(const Shape& shape);
/// The shape's size: the largest extent of its bounding box, world units. prt-synth --noise is
/// relative to it.
double shape_size(const Shape& shape);
/// Axis-aligned bounds of the surface, world frame: {min, max}.
std::array<Vec3, 2> shape_bounds(const Shape& shape);

/// The shape as a JSON object text: {"kind": ..., per-kind parameters, "scale", "offset"}.
std::string shape_to_json(const Shape& shape);
/// Reads shape_to_json()'s output back (validated); `label` names the source in errors.
Shape shape_from_json(const std::string& json_text, const std::string& label);
/// The shape of a synthetic pool: the "shape" of the last prt-synth entry of its provenance JSON
/// (PoolFile::provenance_json()). Throws prt::Error when there is none.
Shape shape_from_provenance(const std::string& provenance_json, const std::string& label);

}  // namespace prt::synth
