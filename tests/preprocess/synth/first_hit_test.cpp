// Exact ray casting against the analytic shapes (analytic.h first_hit) checked against brute force:
// fixed-step marching of the signed distance along the ray with a bisection finish, closed-form
// grazing cases written out here, and the same rays at scales 1e-3 and 1e4 with offsets 1e6.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include "analytic.h"
#include "prt/error.h"
#include "synth_test_util.h"

using namespace prt::synth;
using prt::synth_test::dot;
using prt::synth_test::len;
using prt::synth_test::sub;

namespace {

Vec3 add(const Vec3& a, const Vec3& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
Vec3 mul(const Vec3& a, double s) {
    return {a[0] * s, a[1] * s, a[2] * s};
}
Shape make_shape(ShapeKind kind) {
    return prt::synth_test::make_shape(kind, {1.25, {1.0, 0.35}, 1.5, 3.0, {1.0, 0.1, 0.5}});
}

constexpr ShapeKind k_kinds[] = {ShapeKind::sphere, ShapeKind::torus, ShapeKind::cube,
                                 ShapeKind::plane,  ShapeKind::room,  ShapeKind::ring};

/// Brute force: march the signed distance with a fixed step from t = 0 to t_end; at the first
/// sign change (or zero), bisect; accept the root only where |sd| is ~0 (the plane's sign also
/// flips beside the square, with no surface there) and go on otherwise.
std::optional<double> march(const Shape& s, const Vec3& o, const Vec3& d, double t_end, double step) {
    auto sd = [&](double t) { return signed_distance(s, add(o, mul(d, t))); };
    const double tol = 1e-9 * shape_size(s);
    double prev_t = 0, prev = sd(0);
    if (prev == 0) return 0.0;
    for (double t = step; t <= t_end + step; t += step) {
        const double cur = sd(t);
        if (cur == 0) return t;
        if ((cur < 0) != (prev < 0)) {
            double a = prev_t, b = t;
            for (int k = 0; k < 200; ++k) {
                const double m = 0.5 * (a + b);
                ((sd(m) < 0) == (prev < 0) ? a : b) = m;
            }
            if (std::fabs(sd(b)) <= tol) return b;
        }
        prev_t = t;
        prev = cur;
    }
    return std::nullopt;
}

Vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    for (;;) {
        const Vec3 v{g(rng), g(rng), g(rng)};
        const double l = len(v);
        if (l > 1e-6) return mul(v, 1.0 / l);
    }
}

}  // namespace

TEST(FirstHit, MatchesMarchingOnRandomRays) {
    std::mt19937 rng(7);
    for (ShapeKind kind : k_kinds) {
        const Shape s = make_shape(kind);
        const double size = shape_size(s);
        const auto box = shape_bounds(s);
        std::uniform_real_distribution<double> u01(0, 1);
        int hits = 0, misses = 0, grazing_only_exact = 0, touching = 0, rays = 1000;
        for (int i = 0; i < rays; ++i) {
            // Origins in a box 3x the shape's, the room's mostly inside it; directions aimed at a
            // random point of the bounding box (many hits) or random (misses, exits).
            const double spread = kind == ShapeKind::room && i % 4 != 0 ? 0.48 : 1.5;
            Vec3 o;
            for (int a = 0; a < 3; ++a) o[a] = (2 * u01(rng) - 1) * spread * size;
            Vec3 target;
            for (int a = 0; a < 3; ++a) target[a] = box[0][a] + u01(rng) * (box[1][a] - box[0][a]);
            Vec3 d = i % 3 == 0 ? random_unit(rng) : mul(sub(target, o), 1.0 / len(sub(target, o)));
            if (i % 5 == 4) {
                // Grazing: along a tangent of a surface point, 1e-7 of the size off it (either side).
                const SurfacePoint sp = closest(s, target);
                Vec3 t = random_unit(rng);
                t = sub(t, mul(sp.normal, dot(t, sp.normal)));
                d = mul(t, 1.0 / len(t));
                const double off = (i % 2 ? 1e-7 : -1e-7) * size;
                o = sub(add(sp.point, mul(sp.normal, off)), mul(d, (0.5 + u01(rng)) * size));
            }
            const double t_end = len(o) + 2 * size;
            const std::optional<RayHit> h = first_hit(s, o, d);
            const std::optional<double> m = march(s, o, d, t_end, size / 1000);
            SCOPED_TRACE(std::string(shape_name(kind)) + " ray " + std::to_string(i));
            const double step = size / 1000, tol = 1e-9 * size;
            const bool grazing = i % 5 == 4;
            if (m) {
                ASSERT_TRUE(h) << "marching found a hit at t = " << *m;
            }
            if (h && (!m || h->t < *m - tol)) {
                // Exact found a surface point marching did not see: from below the room through
                // the floor under the cube (surface, but the cube's inside lies beyond it, so no
                // sign change), or a graze: a dip into a solid shallower than the marching step.
                const Room& r = s.room;
                if (kind == ShapeKind::room && h->part == k_room_floor && signed_distance(s, o) < 0 &&
                    std::hypot(h->point[0] - r.cube_center[0], h->point[2] - r.cube_center[2]) <
                        r.cube_edge * std::sqrt(0.5)) {
                    ++touching;
                } else {
                    double lowest = INFINITY;
                    for (double t = h->t - step; t <= h->t + step; t += step / 1000)
                        lowest = std::min(lowest, signed_distance(s, add(o, mul(d, t))));
                    EXPECT_GE(lowest, -step) << "a deep crossing that marching should have seen";
                    if (!grazing) ++grazing_only_exact;
                }
            } else if (m) {
                ++hits;
                EXPECT_NEAR(h->t, *m, tol) << "part " << h->part;
            } else if (!h) {
                ++misses;
            }
            if (h) {
                EXPECT_GE(h->t, 0);
                EXPECT_LE(std::fabs(signed_distance(s, h->point)), 1e-12 * size) << "hit off the surface";
                EXPECT_LE(len(sub(h->point, add(o, mul(d, h->t)))), 1e-12 * (size + len(o)));
                EXPECT_NEAR(len(h->normal), 1.0, 1e-12);
                const SurfacePoint sp = closest(s, h->point);
                // The normal is the surface's (corners and edges: one of the faces meeting there).
                if (std::fabs(dot(sp.normal, h->normal) - 1) > 1e-9) {
                    const bool cube_edge =
                        kind == ShapeKind::cube || kind == ShapeKind::room || kind == ShapeKind::ring;
                    EXPECT_TRUE(cube_edge) << "normal differs from closest()'s away from an edge";
                }
            }
        }
        EXPECT_GT(hits, rays / 4) << shape_name(kind);
        EXPECT_LE(grazing_only_exact, rays / 50) << shape_name(kind);
        if (kind != ShapeKind::room) {
            EXPECT_GT(misses, 10) << shape_name(kind);
        }
        EXPECT_LE(touching, rays / 50) << shape_name(kind);
    }
}

TEST(FirstHit, PartsAndNormalsMatchTheFaceHit) {
    // Axis rays from outside the cube hit the face they point at; the room from its centre hits
    // each wall; the ring's parts from rays that can only meet one of them.
    Shape cube = make_shape(ShapeKind::cube);
    for (int face = 0; face < 6; ++face) {
        Vec3 o{0.1, -0.2, 0.05};
        const int axis = face / 2;
        const double side = face % 2 ? -1.0 : 1.0;
        o[axis] = 5 * side;
        Vec3 d{0, 0, 0};
        d[axis] = -side;
        const auto h = first_hit(cube, o, d);
        ASSERT_TRUE(h);
        EXPECT_EQ(h->part, face);
        EXPECT_EQ(h->normal[axis], side);
        EXPECT_EQ(h->point[axis], side * 0.75) << "snapped exactly onto the face";
        EXPECT_DOUBLE_EQ(h->t, 5 - 0.75);
    }
    const Shape room = make_shape(ShapeKind::room);
    const struct {
        Vec3 d;
        int part;
    } walls[] = {{{0, -1, 0}, k_room_floor},     {{0, 1, 0}, k_room_ceiling},
                 {{-1, 0, 0}, k_room_left_wall}, {{1, 0, 0}, k_room_right_wall},
                 {{0, 0, -1}, k_room_back_wall}, {{0, 0, 1}, k_room_front_wall}};
    for (const auto& w : walls) {
        const auto h = first_hit(room, {0, 0.5, 0.6}, w.d);  // above both objects
        ASSERT_TRUE(h);
        EXPECT_EQ(h->part, w.part) << room_part_name(w.part);
        EXPECT_DOUBLE_EQ(dot(h->normal, w.d), -1.0) << "wall normals point into the room";
    }
    const Room& r = room.room;
    auto sphere_hit = first_hit(room, add(r.sphere_center, {0, 0.7, 0}), {0, -1, 0});
    ASSERT_TRUE(sphere_hit);
    EXPECT_EQ(sphere_hit->part, k_room_sphere);
    EXPECT_NEAR(sphere_hit->t, 0.7 - r.sphere_radius, 1e-15);
    auto cube_hit = first_hit(room, add(r.cube_center, {0, 0.7, 0}), {0, -1, 0});
    ASSERT_TRUE(cube_hit);
    EXPECT_EQ(cube_hit->part, k_room_cube);
    EXPECT_NEAR(cube_hit->t, 0.7 - 0.5 * r.cube_edge, 1e-15);
    EXPECT_NEAR(cube_hit->normal[1], 1.0, 1e-15);
    // From outside the room: the wall's outer side (normal still into the room).
    auto outside = first_hit(room, {0, 0, 5}, {0, 0, -1});
    ASSERT_TRUE(outside);
    EXPECT_EQ(outside->part, k_room_front_wall);
    EXPECT_DOUBLE_EQ(outside->t, 4.0);

    const Shape ring = make_shape(ShapeKind::ring);  // r 1, t 0.1, h 0.5
    auto from = [&](Vec3 o, Vec3 d) { return first_hit(ring, o, d); };
    auto h = from({-5, 0.1, 0}, {1, 0, 0});
    ASSERT_TRUE(h);
    EXPECT_EQ(h->part, k_ring_outer);
    EXPECT_DOUBLE_EQ(h->t, 5 - 1.1);
    h = from({0, 0.1, 0}, {1, 0, 0});  // from the axis: the inner wall
    ASSERT_TRUE(h);
    EXPECT_EQ(h->part, k_ring_inner);
    EXPECT_DOUBLE_EQ(h->t, 1.0);
    EXPECT_DOUBLE_EQ(h->normal[0], -1.0);
    h = from({1.05, 3, 0}, {0, -1, 0});
    ASSERT_TRUE(h);
    EXPECT_EQ(h->part, k_ring_top);
    EXPECT_DOUBLE_EQ(h->t, 3 - 0.25);
    h = from({0, 3, 0}, {0, -1, 0});  // down the axis: through the hole
    EXPECT_FALSE(h);
    h = from({1.05, -3, 0}, {0, 1, 0});  // from below: the unsampled bottom
    ASSERT_TRUE(h);
    EXPECT_EQ(h->part, k_ring_part_count);
    // Through the hole and out the far side: outer wall entry, inner exit, inner entry, outer exit.
    h = from({-5, 0, 0.5}, {1, 0, 0});
    ASSERT_TRUE(h);
    EXPECT_DOUBLE_EQ(h->t, 5 - std::sqrt(1.1 * 1.1 - 0.25));
    h = from({-std::sqrt(1.1 * 1.1 - 0.25) + 1e-3, 0, 0.5}, {1, 0, 0});  // inside the wall: its exit
    ASSERT_TRUE(h);
    EXPECT_EQ(h->part, k_ring_inner);
    EXPECT_NEAR(h->t, std::sqrt(1.1 * 1.1 - 0.25) - 1e-3 - std::sqrt(1 - 0.25), 1e-15);
}

TEST(FirstHit, GrazingRaysResolveAsTheClosedFormSays) {
    // The sphere: a line at distance r (1 -+ eps) from the centre hits / misses.
    const Shape sphere = make_shape(ShapeKind::sphere);  // r 1.25
    for (double eps : {1e-4, 1e-7, 1e-10, 1e-13}) {
        const double y = 1.25 * (1 - eps);
        auto h = first_hit(sphere, {-5, y, 0}, {1, 0, 0});
        ASSERT_TRUE(h) << eps;
        const double x = -std::sqrt((1.25 - y) * (1.25 + y));
        EXPECT_NEAR(h->t, 5 + x, 1e-12) << eps;
        EXPECT_FALSE(first_hit(sphere, {-5, 1.25 * (1 + eps), 0}, {1, 0, 0})) << eps;
    }
    // The torus (R 1, r 0.35): a horizontal line through the axis at height r -+ eps meets the
    // tube's top at |x| = R -+ sqrt(r^2 - y^2); above the top it misses. And the outer silhouette.
    const Shape torus = make_shape(ShapeKind::torus);
    for (double eps : {1e-3, 1e-6, 1e-9, 1e-12}) {
        const double y = 0.35 - eps;
        auto h = first_hit(torus, {-5, y, 0}, {1, 0, 0});
        ASSERT_TRUE(h) << eps;
        const double w = std::sqrt((0.35 - y) * (0.35 + y));
        EXPECT_NEAR(h->t, 5 - 1 - w, 1e-12 + 1e-16 / (w / 0.35)) << eps;
        EXPECT_FALSE(first_hit(torus, {-5, 0.35 + eps, 0}, {1, 0, 0})) << eps;
        // Beyond the first tube the line meets the second: start past the first.
        h = first_hit(torus, {0, y, 0}, {1, 0, 0});
        ASSERT_TRUE(h) << eps;
        EXPECT_NEAR(h->t, 1 - w, 1e-12 + 1e-16 / (w / 0.35)) << eps;
        // Outer silhouette in the plane y = 0: the line z = R + r -+ eps.
        const double z = 1.35 - eps;
        h = first_hit(torus, {-5, 0, z}, {1, 0, 0});
        ASSERT_TRUE(h) << eps;
        EXPECT_NEAR(h->t, 5 - std::sqrt((1.35 - z) * (1.35 + z)), 1e-12 + 1e-16 / std::sqrt(eps)) << eps;
        EXPECT_FALSE(first_hit(torus, {-5, 0, 1.35 + eps}, {1, 0, 0})) << eps;
    }
    // A line through the hole along the axis misses; one tilted to touch the inner equator hits.
    EXPECT_FALSE(first_hit(torus, {0, 5, 0}, {0, -1, 0}));
    // The cube (e 1.5): a line along a face, just inside / on / outside it.
    const Shape cube = make_shape(ShapeKind::cube);
    for (double eps : {1e-6, 1e-12, 0.0}) {
        auto h = first_hit(cube, {-5, 0.75 - eps, 0.2}, {1, 0, 0});
        ASSERT_TRUE(h) << eps;
        EXPECT_EQ(h->t, 5 - 0.75);
        if (eps > 0) {
            EXPECT_FALSE(first_hit(cube, {-5, 0.75 + eps, 0.2}, {1, 0, 0}));
        }
    }
    auto corner = first_hit(cube, {3, 3, 3}, mul(Vec3{-1, -1, -1}, 1 / std::sqrt(3.0)));
    ASSERT_TRUE(corner);
    EXPECT_NEAR(len(sub(corner->point, {0.75, 0.75, 0.75})), 0, 1e-15);
    // The plane: a nearly parallel line crosses at the closed-form point; an exactly parallel one
    // (in the plane) has no crossing.
    const Shape plane = make_shape(ShapeKind::plane);
    auto h = first_hit(plane, {-1, 1e-9, 0.3}, {1, -1e-9, 0});
    ASSERT_TRUE(h);
    EXPECT_NEAR(h->point[0], 0.0, 1e-15);
    EXPECT_FALSE(first_hit(plane, {-1, 0, 0.3}, {1, 0, 0}));
    EXPECT_FALSE(first_hit(plane, {-1, 1e-9, 1.5 + 1e-9}, {1, -1e-9, 0})) << "beside the square";
    // The room: lines tangent to its sphere from inside, missing it they reach the back wall.
    const Shape room = make_shape(ShapeKind::room);
    const Room& r = room.room;
    for (double eps : {1e-6, 1e-11}) {
        const Vec3 o = add(r.sphere_center, {0, r.sphere_radius * (1 - eps), 0.9});
        h = first_hit(room, o, {0, 0, -1});
        ASSERT_TRUE(h);
        EXPECT_EQ(h->part, k_room_sphere);
        h = first_hit(room, add(o, {0, 2 * eps * r.sphere_radius, 0}), {0, 0, -1});
        ASSERT_TRUE(h);
        EXPECT_EQ(h->part, k_room_back_wall);
        EXPECT_NEAR(h->t, o[2] + 1.0, 1e-15);
    }
}

TEST(FirstHit, MaxDistanceAndBadInput) {
    const Shape sphere = make_shape(ShapeKind::sphere);
    EXPECT_TRUE(first_hit(sphere, {-5, 0, 0}, {1, 0, 0}, 3.75));
    EXPECT_FALSE(first_hit(sphere, {-5, 0, 0}, {1, 0, 0}, 3.7499));
    // Non-unit directions: t in units of |dir|.
    auto h = first_hit(sphere, {-5, 0, 0}, {2, 0, 0});
    ASSERT_TRUE(h);
    EXPECT_DOUBLE_EQ(h->t, 3.75 / 2);
    // From inside a solid: its exit.
    h = first_hit(sphere, {0.5, 0, 0}, {1, 0, 0});
    ASSERT_TRUE(h);
    EXPECT_DOUBLE_EQ(h->t, 0.75);
    EXPECT_THROW(first_hit(sphere, {0, 0, 0}, {0, 0, 0}), prt::Error);
    EXPECT_THROW(first_hit(sphere, {NAN, 0, 0}, {1, 0, 0}), prt::Error);
    EXPECT_THROW(first_hit(sphere, {0, 0, 0}, {INFINITY, 0, 0}), prt::Error);
}

TEST(FirstHit, ScaleAndOffsetAreExactToRounding) {
    // The same rays in the shape's own frame and placed at scale 1e-3 / 1e4 with an offset of 1e6:
    // the world hit is the local hit placed, to the rounding of world coordinates of size 1e6.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u01(0, 1);
    for (ShapeKind kind : k_kinds) {
        const Shape local = make_shape(kind);
        const double size = shape_size(local);
        for (double scale : {1e-3, 1e4}) {
            Shape world = local;
            world.scale = scale;
            world.offset = {1e6, -1e6, 2.5e6};
            const double ulp =
                std::nextafter(2.5e6 + 2 * scale * size, INFINITY) - (2.5e6 + 2 * scale * size);
            int compared = 0;
            for (int i = 0; i < 300; ++i) {
                const double spread = kind == ShapeKind::room ? 0.45 : 1.5;
                Vec3 o, target;
                for (int a = 0; a < 3; ++a) o[a] = (2 * u01(rng) - 1) * spread * size;
                for (int a = 0; a < 3; ++a) target[a] = (u01(rng) - 0.5) * size;
                const Vec3 d = mul(sub(target, o), 3.7 / len(sub(target, o)));  // not unit
                const auto hl = first_hit(local, o, d);
                // Placed exactly: o and d scaled, offset added (rounded to world doubles).
                const Vec3 ow = add(mul(o, scale), world.offset);
                const auto hw = first_hit(world, ow, d);
                SCOPED_TRACE(std::string(shape_name(kind)) + " scale " + std::to_string(scale) + " ray " +
                             std::to_string(i));
                // Rays that cross within rounding of a silhouette or an edge may differ.
                if (hl && std::fabs(dot(hl->normal, d) / len(d)) < 0.05) continue;
                if (!hl) {
                    if (hw) {
                        EXPECT_LE(std::fabs(dot(hw->normal, d)) / len(d), 1e-6);
                    }
                    continue;
                }
                ASSERT_TRUE(hw);
                ++compared;
                const double tol = 64 * ulp / 0.05;  // origin rounding, magnified at 87 degrees
                EXPECT_NEAR(hw->t, hl->t * scale, tol);
                for (int a = 0; a < 3; ++a)
                    EXPECT_NEAR(hw->point[a], world.offset[a] + scale * hl->point[a], tol);
                EXPECT_LE(std::fabs(signed_distance(world, hw->point)), 1e-12 * scale * size + 8 * ulp);
                EXPECT_EQ(hw->part, hl->part);
            }
            EXPECT_GT(compared, 100) << shape_name(kind);
        }
    }
}
