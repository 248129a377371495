// The analytic ground truth (preprocess/synth/analytic.h) against brute force: dense samples of
// each surface, minimised by hand, and the shapes' implicit equations written out independently.
#include "analytic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "prt/error.h"

using namespace prt::synth;

namespace {

constexpr double k_pi = 3.14159265358979323846;

double dist(const Vec3& a, const Vec3& b) {
    return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}
double len(const Vec3& a) {
    return std::hypot(a[0], a[1], a[2]);
}

/// Brute-force distance from p to a surface given as a parametric map over [0,1]^2 on a grid.
double brute_distance(const Vec3& p, int steps, const std::function<Vec3(double, double)>& surface) {
    double best = INFINITY;
    for (int i = 0; i <= steps; ++i)
        for (int j = 0; j <= steps; ++j)
            best = std::min(best, dist(p, surface(double(i) / steps, double(j) / steps)));
    return best;
}

/// One face of an axis-aligned box [c - h, c + h]: axis a, side s, parameters (u, v) in [0,1].
Vec3 box_face(const Vec3& c, double h, int a, double s, double u, double v) {
    Vec3 p = c;
    p[a] += s * h;
    p[(a + 1) % 3] += (2 * u - 1) * h;
    p[(a + 2) % 3] += (2 * v - 1) * h;
    return p;
}

Vec3 random_point(std::mt19937& rng, double extent) {
    std::uniform_real_distribution<double> u(-extent, extent);
    return {u(rng), u(rng), u(rng)};
}

void expect_unit(const Vec3& n) {
    EXPECT_NEAR(len(n), 1.0, 1e-12);
}

}  // namespace

TEST(Analytic, SphereMatchesBruteForce) {
    const Sphere s{1.5};
    std::mt19937 rng(1);
    for (int k = 0; k < 30; ++k) {
        const Vec3 p = random_point(rng, 3.0);
        const SurfacePoint r = closest(s, p);
        EXPECT_NEAR(len(r.point), 1.5, 1e-12);                // on the sphere
        EXPECT_NEAR(r.signed_distance, len(p) - 1.5, 1e-12);  // analytic
        EXPECT_NEAR(std::fabs(r.signed_distance), dist(p, r.point), 1e-12);
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(r.normal[a], p[a] / len(p), 1e-12);
        // Brute force over (z, phi): no surface point is closer than the claimed one.
        const double brute = brute_distance(p, 200, [](double u, double v) {
            const double y = 1 - 2 * u, ring = std::sqrt(std::max(0.0, 1 - y * y));
            return Vec3{1.5 * ring * std::cos(2 * k_pi * v), 1.5 * y, 1.5 * ring * std::sin(2 * k_pi * v)};
        });
        EXPECT_LE(std::fabs(r.signed_distance), brute + 1e-12);
        EXPECT_NEAR(std::fabs(r.signed_distance), brute, 0.03);  // grid spacing ~ 1.5 * pi / 200
    }
}

TEST(Analytic, TorusMatchesBruteForceAndImplicitEquation) {
    const double big = 1.0, small = 0.3;
    const Torus t{big, small};
    auto implicit = [&](const Vec3& p) {  // (sqrt(x^2 + z^2) - R)^2 + y^2 - r^2
        const double q = std::hypot(p[0], p[2]) - big;
        return q * q + p[1] * p[1] - small * small;
    };
    std::mt19937 rng(2);
    for (int k = 0; k < 25; ++k) {
        const Vec3 p = random_point(rng, 1.6);
        const SurfacePoint r = closest(t, p);
        EXPECT_NEAR(implicit(r.point), 0.0, 1e-12);
        EXPECT_NEAR(std::fabs(r.signed_distance), dist(p, r.point), 1e-12);
        EXPECT_EQ(r.signed_distance < 0, implicit(p) < 0) << "sign: inside the tube is negative";
        // Normal = normalised gradient of the implicit function at the closest point.
        const double q = std::hypot(r.point[0], r.point[2]);
        const Vec3 g{2 * (q - big) * r.point[0] / q, 2 * r.point[1], 2 * (q - big) * r.point[2] / q};
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(r.normal[a], g[a] / len(g), 1e-9);
        const double brute = brute_distance(p, 400, [&](double u, double v) {
            const double th = 2 * k_pi * u, ph = 2 * k_pi * v;
            const double ring = big + small * std::cos(th);
            return Vec3{ring * std::cos(ph), small * std::sin(th), ring * std::sin(ph)};
        });
        EXPECT_LE(std::fabs(r.signed_distance), brute + 1e-12);
        EXPECT_NEAR(std::fabs(r.signed_distance), brute, 0.02);
    }
}

TEST(Analytic, CubeMatchesBruteForce) {
    const Cube c{2.0};
    std::mt19937 rng(3);
    for (int k = 0; k < 40; ++k) {
        const Vec3 p = random_point(rng, k < 20 ? 1.0 : 2.5);  // half inside, half mostly outside
        const SurfacePoint r = closest(c, p);
        const double m = std::max({std::fabs(r.point[0]), std::fabs(r.point[1]), std::fabs(r.point[2])});
        EXPECT_NEAR(m, 1.0, 1e-12) << "closest point on the surface";
        const bool inside = std::fabs(p[0]) < 1 && std::fabs(p[1]) < 1 && std::fabs(p[2]) < 1;
        EXPECT_EQ(r.signed_distance < 0, inside);
        double brute = INFINITY;
        for (int a = 0; a < 3; ++a)
            for (double s : {-1.0, 1.0})
                brute = std::min(brute, brute_distance(p, 100, [&](double u, double v) {
                                     return box_face({0, 0, 0}, 1.0, a, s, u, v);
                                 }));
        EXPECT_LE(std::fabs(r.signed_distance), brute + 1e-12);
        EXPECT_NEAR(std::fabs(r.signed_distance), brute, 0.015);
        expect_unit(r.normal);
        // The normal is a face normal of a face containing the closest point.
        int axis = 0;
        for (int a = 0; a < 3; ++a)
            if (r.normal[a] != 0) axis = a;
        EXPECT_NEAR(r.point[axis], r.normal[axis], 1e-12);
        EXPECT_EQ(r.part, 2 * axis + (r.normal[axis] < 0 ? 1 : 0));
    }
}

TEST(Analytic, PlaneIsAFiniteSquare) {
    const Plane s{2.0};
    // Above the middle: straight down; beyond an edge: to the edge; below: negative.
    SurfacePoint r = closest(s, {0.3, 0.5, -0.2});
    EXPECT_DOUBLE_EQ(r.signed_distance, 0.5);
    EXPECT_EQ(r.point, (Vec3{0.3, 0, -0.2}));
    EXPECT_EQ(r.normal, (Vec3{0, 1, 0}));
    r = closest(s, {3.0, 0.0, 0.0});
    EXPECT_DOUBLE_EQ(r.signed_distance, 2.0);
    r = closest(s, {2.0, -1.0, 2.0});
    EXPECT_NEAR(r.signed_distance, -std::sqrt(3.0), 1e-15);
    EXPECT_EQ(r.point, (Vec3{1, 0, 1}));
}

TEST(Analytic, RoomPartsSignsAndBruteForce) {
    const Room room = Room::standard(2.0);
    Shape shape;
    shape.kind = ShapeKind::room;
    shape.room = room;
    ASSERT_NO_THROW(validate(shape));
    // Hand-picked points: near each wall, inside the objects, outside the room.
    struct Case {
        Vec3 p;
        int part;
        double sd;
    };
    const double yaw = room.cube_yaw_degrees * k_pi / 180;
    for (const Case& c :
         {Case{{0.0, -0.95, 0.8}, k_room_floor, 0.05}, Case{{0.1, 0.9, 0.0}, k_room_ceiling, 0.1},
          Case{{-0.97, 0.2, 0.0}, k_room_left_wall, 0.03}, Case{{0.9, 0.3, -0.5}, k_room_right_wall, 0.1},
          Case{{0.0, 0.2, -0.92}, k_room_back_wall, 0.08}, Case{{0.1, 0.3, 0.96}, k_room_front_wall, 0.04},
          Case{{0.0, 0.0, 1.5}, k_room_front_wall, -0.5},
          Case{{room.sphere_center[0], room.sphere_center[1] + 0.1, room.sphere_center[2]},
               k_room_sphere,
               -0.3},
          Case{{room.sphere_center[0], room.sphere_center[1] + 0.5, room.sphere_center[2]},
               k_room_sphere,
               0.1}}) {
        const SurfacePoint r = closest(room, c.p);
        EXPECT_EQ(r.part, c.part) << c.p[0] << "," << c.p[1] << "," << c.p[2];
        EXPECT_NEAR(r.signed_distance, c.sd, 1e-12);
    }
    // Walls face inward: a point just inside the left wall gets normal +x.
    EXPECT_EQ(closest(room, {-0.99, 0, 0}).normal, (Vec3{1, 0, 0}));
    EXPECT_EQ(closest(room, {0, -0.99, 0.9}).normal, (Vec3{0, 1, 0}));
    // Above the cube's top face centre: normal +y, distance to the top.
    const double top = room.cube_center[1] + 0.5 * room.cube_edge;
    SurfacePoint r = closest(room, {room.cube_center[0], top + 0.05, room.cube_center[2]});
    EXPECT_EQ(r.part, k_room_cube);
    EXPECT_NEAR(r.signed_distance, 0.05, 1e-12);
    EXPECT_NEAR(r.normal[1], 1.0, 1e-12);
    // Beside the cube along its turned +x face normal (cos yaw, 0, -sin yaw).
    const Vec3 nx{std::cos(yaw), 0, -std::sin(yaw)};
    const Vec3 side{room.cube_center[0] + nx[0] * (0.5 * room.cube_edge + 0.02), room.cube_center[1],
                    room.cube_center[2] + nx[2] * (0.5 * room.cube_edge + 0.02)};
    r = closest(room, side);
    EXPECT_EQ(r.part, k_room_cube);
    EXPECT_NEAR(r.signed_distance, 0.02, 1e-12);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(r.normal[a], nx[a], 1e-12);

    // Brute force over every part surface (walls, sphere, the cube's 6 faces) at random points.
    std::mt19937 rng(4);
    for (int k = 0; k < 12; ++k) {
        const Vec3 p = random_point(rng, 1.1);
        const SurfacePoint q = closest(room, p);
        double brute = INFINITY;
        for (int a = 0; a < 3; ++a)
            for (double s : {-1.0, 1.0}) {
                brute = std::min(brute, brute_distance(p, 60, [&](double u, double v) {
                                     return box_face({0, 0, 0}, 1.0, a, s, u, v);
                                 }));
                brute = std::min(brute, brute_distance(p, 60, [&](double u, double v) {
                                     const Vec3 l = box_face({0, 0, 0}, 0.5 * room.cube_edge, a, s, u, v);
                                     const double c = std::cos(yaw), sn = std::sin(yaw);
                                     return Vec3{room.cube_center[0] + c * l[0] + sn * l[2],
                                                 room.cube_center[1] + l[1],
                                                 room.cube_center[2] - sn * l[0] + c * l[2]};
                                 }));
            }
        brute = std::min(brute, std::fabs(dist(p, room.sphere_center) - room.sphere_radius));
        EXPECT_LE(std::fabs(q.signed_distance), brute + 1e-12);
        EXPECT_NEAR(std::fabs(q.signed_distance), brute, 0.04);
        EXPECT_NEAR(std::fabs(q.signed_distance), dist(p, q.point), 1e-12);
        // Sign: air = inside the box, outside the sphere and the (turned) cube.
        const Vec3 d{p[0] - room.cube_center[0], p[1] - room.cube_center[1], p[2] - room.cube_center[2]};
        const Vec3 l{std::cos(yaw) * d[0] - std::sin(yaw) * d[2], d[1],
                     std::sin(yaw) * d[0] + std::cos(yaw) * d[2]};
        const bool in_cube =
            std::max({std::fabs(l[0]), std::fabs(l[1]), std::fabs(l[2])}) < 0.5 * room.cube_edge;
        const bool in_box = std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])}) < 1.0;
        const bool air = in_box && !in_cube && dist(p, room.sphere_center) > room.sphere_radius;
        EXPECT_EQ(q.signed_distance > 0, air);
    }
}

TEST(Analytic, ScaleAndOffsetTransformTheShape) {
    Shape s;
    s.kind = ShapeKind::torus;
    s.torus = {2.0, 0.5};
    s.scale = 3.0;
    s.offset = {1e6, -2, 5};
    const Vec3 local{2.4, 0.3, -0.7};
    const Vec3 world{local[0] * 3 + 1e6, local[1] * 3 - 2, local[2] * 3 + 5};
    const SurfacePoint a = closest(s.torus, local);
    const SurfacePoint b = closest(s, world);
    EXPECT_NEAR(b.signed_distance, 3 * a.signed_distance, 1e-9);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(b.point[i], a.point[i] * 3 + s.offset[i], 1e-9);
        EXPECT_NEAR(b.normal[i], a.normal[i], 1e-9);
    }
    EXPECT_NEAR(surface_area(s), 9 * 4 * k_pi * k_pi * 2.0 * 0.5, 1e-9);
    EXPECT_DOUBLE_EQ(shape_size(s), 3 * 2 * 2.5);
    EXPECT_EQ(signed_distance(s, world), b.signed_distance);
}

TEST(Analytic, JsonAndProvenanceRebuildTheShape) {
    Shape s;
    s.kind = ShapeKind::room;
    s.room = Room::standard(3.0);
    s.scale = 0.1;
    s.offset = {1, 2, 3};
    const Shape back = shape_from_json(shape_to_json(s), "x");
    EXPECT_EQ(back.kind, ShapeKind::room);
    EXPECT_EQ(back.room.size, 3.0);
    EXPECT_EQ(back.room.sphere_center, s.room.sphere_center);
    EXPECT_EQ(back.room.cube_yaw_degrees, s.room.cube_yaw_degrees);
    EXPECT_EQ(back.scale, 0.1);
    EXPECT_EQ(back.offset, s.offset);

    // The last prt-synth entry wins; other tools are skipped.
    const std::string prov = R"([{"tool": "prt-synth", "parameters": {"shape": {"kind": "sphere", "radius": 1,
        "scale": 1, "offset": [0, 0, 0]}}}, {"tool": "prt-synth", "parameters": {"shape": {"kind": "torus",
        "major_radius": 2, "minor_radius": 0.5, "scale": 1, "offset": [0, 0, 0]}}},
        {"tool": "prt-radii", "parameters": {"k": 8}}])";
    const Shape t = shape_from_provenance(prov, "m.pool");
    EXPECT_EQ(t.kind, ShapeKind::torus);
    EXPECT_EQ(t.torus.major_radius, 2.0);
    EXPECT_EQ(t.torus.minor_radius, 0.5);

    auto message = [](const std::string& text) {
        try {
            shape_from_provenance(text, "m.pool");
        } catch (const prt::Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message(R"([{"tool": "prt-import", "parameters": {}}])").find("m.pool: not a synthetic model"),
              std::string::npos);
    EXPECT_NE(message("not json").find("m.pool: provenance: invalid JSON"), std::string::npos);
    EXPECT_NE(message(R"([{"tool": "prt-synth", "parameters": {"shape": {"kind": "torus", "major_radius": 1,
        "minor_radius": 2, "scale": 1, "offset": [0, 0, 0]}}}])")
                  .find("minor radius must be smaller"),
              std::string::npos);
    EXPECT_NE(message(R"([{"tool": "prt-synth", "parameters": {"shape": {"kind": "sphere", "scale": 1,
        "offset": [0, 0, 0]}}}])")
                  .find("missing number \"radius\""),
              std::string::npos);
}

TEST(Analytic, ValidateRejectsBadShapes) {
    auto rejects = [](const Shape& s, const char* fragment) {
        try {
            validate(s);
        } catch (const prt::Error& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
            return;
        }
        ADD_FAILURE() << "accepted, expected: " << fragment;
    };
    Shape s;
    s.sphere.radius = 0;
    rejects(s, "sphere radius");
    s = Shape{};
    s.scale = -1;
    rejects(s, "scale");
    s = Shape{};
    s.offset[1] = NAN;
    rejects(s, "offset");
    s = Shape{};
    s.kind = ShapeKind::torus;
    s.torus = {1.0, 1.0};
    rejects(s, "minor radius must be smaller");
    s = Shape{};
    s.kind = ShapeKind::room;
    s.room = Room::standard(2.0);
    s.room.sphere_radius = 0.9;
    rejects(s, "room sphere must lie inside");
    s.room = Room::standard(2.0);
    s.room.cube_center = {-0.3, -0.7, -0.2};
    rejects(s, "must not overlap");
    s.room = Room::standard(2.0);
    s.room.cube_yaw_degrees = 45;
    s.room.cube_center[0] = 0.7;
    rejects(s, "room cube must lie inside");
}

TEST(Analytic, RoomColorsIdentifyParts) {
    for (int p = 0; p < k_room_part_count; ++p) EXPECT_EQ(room_part_from_color(room_part_color(p)), p);
    EXPECT_EQ(room_part_from_color({1, 2, 3, 255}), -1);
    // Color bleeding needs a red left wall and a green right wall.
    const auto left = room_part_color(k_room_left_wall), right = room_part_color(k_room_right_wall);
    EXPECT_GT(left.r, 2 * left.g);
    EXPECT_GT(right.g, 2 * right.r);
}
