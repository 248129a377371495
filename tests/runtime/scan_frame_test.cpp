// The default view of a scan (scan_frame.h, RenderScene::default_camera) on synthetic data whose
// answer is known by construction: robust bounds that drop far outliers and keep thin parts, the
// up direction of a plane with objects standing on it in several orientations (with a lower floor
// beyond the plane's edge that outnumbers the objects), of sensor directions on a circle (a
// turntable), the fallback, axis snapping, and a camera that frames every point tightly.
#include "prt/runtime/scan_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "prt/runtime/render_scene.h"
#include "test_scene.h"

namespace prt::test {
namespace {

using rt::DVec3;

constexpr double k_pi = 3.14159265358979323846;

D3 cross3(const D3& a, const D3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double angle_degrees(const D3& a, const D3& b) {
    return std::acos(std::clamp(d3_dot(d3_norm(a), d3_norm(b)), -1.0, 1.0)) * 180.0 / k_pi;
}

/// A right-handed frame (a, b, up) around a unit up.
void frame_of(const D3& up, D3& a, D3& b) {
    a = d3_norm(cross3(up, std::fabs(up[0]) < 0.9 ? D3{1, 0, 0} : D3{0, 1, 0}));
    b = cross3(up, a);
}

/// Points (local frame = world, origin 0) with normals, as pool arrays.
struct Cloud {
    std::vector<pool::Float3> p, n;
    void add(const D3& pos, const D3& nrm) {
        p.push_back({static_cast<float>(pos[0]), static_cast<float>(pos[1]), static_cast<float>(pos[2])});
        n.push_back({static_cast<float>(nrm[0]), static_cast<float>(nrm[1]), static_cast<float>(nrm[2])});
    }
};

/// A table top (the square [-1, 1]^2 at height 0, 60 x 60 points, normals up) with three balls
/// standing on it (their parts above the top), and a floor 0.8 below beyond the table's edge with
/// more points than the balls (so "most other points" would point down), all around `up`.
Cloud table_scene(const D3& up) {
    D3 a, b;
    frame_of(up, a, b);
    Cloud c;
    auto at = [&](double s, double t, double h) {
        return d3_add(d3_add(d3_mul(a, s), d3_mul(b, t)), d3_mul(up, h));
    };
    for (int i = 0; i < 60; ++i)
        for (int j = 0; j < 60; ++j) c.add(at(-1 + (i + 0.5) / 30.0, -1 + (j + 0.5) / 30.0, 0), up);
    const double cs[3][2] = {{-0.5, -0.4}, {0.3, 0.5}, {0.5, -0.3}};
    for (const auto& ctr : cs) {
        for (const TestPoint& q : sphere_points({0, 0, 0}, 0.2, 700)) {  // resting on the top
            const D3 local = q.position;                                 // sphere_points: y is the pole axis
            c.add(at(ctr[0] + local[0], ctr[1] + local[2], 0.2 + local[1]),
                  d3_add(d3_add(d3_mul(a, q.normal[0]), d3_mul(b, q.normal[2])), d3_mul(up, q.normal[1])));
        }
    }
    for (int i = 0; i < 50; ++i)
        for (int j = 0; j < 50; ++j) c.add(at(1.3 + (i + 0.5) / 25.0, -1 + (j + 0.5) / 25.0, -0.8), up);
    return c;
}

rt::UpDetection detect(const Cloud& c, std::span<const pool::Sensor> sensors = {}) {
    rt::UpInput in;
    in.positions = c.p;
    in.normals = c.n;
    in.sensors = sensors;
    return rt::detect_up(in);
}

TEST(ScanFrame, RobustBoundsDropFarOutliersAndKeepThinParts) {
    std::vector<DVec3> pts;
    // A unit cube's volume on a 21^3 grid, a thin spike 0.3 above its top, 20 points 50 away.
    for (int i = 0; i <= 20; ++i)
        for (int j = 0; j <= 20; ++j)
            for (int k = 0; k <= 20; ++k) pts.push_back({i / 20.0, j / 20.0, k / 20.0});
    for (int i = 1; i <= 30; ++i) pts.push_back({0.5, 1.0 + i * 0.01, 0.5});
    for (int i = 0; i < 20; ++i) pts.push_back({50.0 + i, -40.0, 60.0});
    const rt::Box b = rt::robust_bounds(pts);
    ASSERT_TRUE(b.valid);
    EXPECT_EQ(b.outside, 20u);
    for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(b.lo[a], 0.0) << a;
    EXPECT_DOUBLE_EQ(b.hi[0], 1.0);
    EXPECT_NEAR(b.hi[1], 1.3, 1e-12);  // the spike's tip, beyond the 99th percentile, is kept
    EXPECT_DOUBLE_EQ(b.hi[2], 1.0);
    EXPECT_FALSE(rt::robust_bounds({}).valid);
}

TEST(ScanFrame, TableTopGivesTheUpInEveryOrientation) {
    const D3 ups[] = {{0, 1, 0},
                      {0, -1, 0},
                      {0, 0, 1},
                      {1, 0, 0},
                      d3_norm({1, 1, 1}),
                      d3_norm({0.3, -0.9, 0.35}),
                      d3_norm({-0.2, 0.1, -1})};
    for (const D3& up : ups) {
        const Cloud c = table_scene(up);
        const rt::UpDetection d = detect(c);
        EXPECT_EQ(d.rule, rt::UpRule::plane) << d.description;
        EXPECT_GT(d.plane_fraction, 0.4);
        EXPECT_LT(angle_degrees(d.up, up), 0.5) << "truth " << rt::direction_name(up) << ", found "
                                                << rt::direction_name(d.up) << ": " << d.description;
    }
}

TEST(ScanFrame, ASensorDecidesThePlaneSide) {
    const D3 up = d3_norm({0.3, -0.9, 0.35});
    const Cloud c = table_scene(up);
    // A scanner below the top (an odd scan, but the rule is the sensors' side): the up turns over.
    pool::Sensor below{};
    const D3 sp = d3_mul(up, -3.0);
    for (int a = 0; a < 3; ++a) below.position[a] = sp[a];
    below.kind = pool::k_sensor_point;
    const std::vector<pool::Sensor> sensors{below};
    const rt::UpDetection d = detect(c, sensors);
    EXPECT_EQ(d.rule, rt::UpRule::plane);
    EXPECT_LT(angle_degrees(d.up, d3_mul(up, -1.0)), 0.5) << d.description;
    EXPECT_NE(d.description.find("sensor"), std::string::npos) << d.description;
    // A far sensor (a direction) above: the true up.
    pool::Sensor above{};
    for (int a = 0; a < 3; ++a) above.position[a] = up[a];
    above.kind = pool::k_sensor_direction;
    const std::vector<pool::Sensor> far{above};
    EXPECT_LT(angle_degrees(detect(c, far).up, up), 0.5);
}

TEST(ScanFrame, NearAxisUpsSnapToTheAxis) {
    const double tilt = 2.0 * k_pi / 180.0;
    const rt::UpDetection d = detect(table_scene({std::sin(tilt), std::cos(tilt), 0}));
    EXPECT_TRUE(d.snapped) << d.description;
    EXPECT_EQ(d.up, (DVec3{0, 1, 0}));
    const double big = 10.0 * k_pi / 180.0;
    const rt::UpDetection e = detect(table_scene({std::sin(big), std::cos(big), 0}));
    EXPECT_FALSE(e.snapped);
    EXPECT_NEAR(angle_degrees(e.up, {0, 1, 0}), 10.0, 0.5);
}

/// A closed ball (no dominant plane, normals balanced) or its upper half about `axis` (a dome: the
/// face it rests on is not scanned, so more normals face up).
Cloud ball(const D3& axis, bool dome) {
    D3 a, b;
    frame_of(axis, a, b);
    Cloud c;
    for (const TestPoint& q : sphere_points({0, 0, 0}, 1.0, 6000)) {
        if (dome && q.position[1] < 0) continue;
        const D3 n =
            d3_add(d3_add(d3_mul(a, q.normal[0]), d3_mul(b, q.normal[2])), d3_mul(axis, q.normal[1]));
        c.add(n, n);
    }
    return c;
}

/// `count` direction sensors evenly around `axis` at `elevation` degrees above its plane.
std::vector<pool::Sensor> turntable(const D3& axis, int count, double elevation) {
    D3 a, b;
    frame_of(axis, a, b);
    std::vector<pool::Sensor> s;
    const double e = elevation * k_pi / 180.0;
    for (int i = 0; i < count; ++i) {
        const double phi = 2 * k_pi * i / count;
        const D3 d = d3_add(d3_mul(d3_add(d3_mul(a, std::cos(phi)), d3_mul(b, std::sin(phi))), std::cos(e)),
                            d3_mul(axis, std::sin(e)));
        pool::Sensor x{};
        for (int k = 0; k < 3; ++k) x.position[k] = d[k];
        x.kind = pool::k_sensor_direction;
        s.push_back(x);
    }
    return s;
}

TEST(ScanFrame, TurntableSensorsGiveTheirAxis) {
    const D3 axis = d3_norm({0.2, 0.1, 1.0});
    // Scanners 20 degrees above the turntable: the side they lean to.
    const rt::UpDetection lean = detect(ball(axis, false), turntable(axis, 8, 20.0));
    EXPECT_EQ(lean.rule, rt::UpRule::sensor_plane) << lean.description;
    EXPECT_LT(angle_degrees(lean.up, axis), 0.5) << lean.description;
    const rt::UpDetection below = detect(ball(axis, false), turntable(axis, 8, -20.0));
    EXPECT_LT(angle_degrees(below.up, d3_mul(axis, -1.0)), 0.5) << below.description;
    // Level scanners: the side more surface normals face (the dome's base was never scanned), with
    // two more scans from elsewhere that are not on the circle.
    std::vector<pool::Sensor> s = turntable(axis, 6, 0.0);
    const auto top = turntable(d3_norm({1, 0.3, 0.2}), 2, 0.0);
    s.insert(s.end(), top.begin(), top.end());
    const rt::UpDetection level = detect(ball(axis, true), s);
    EXPECT_EQ(level.rule, rt::UpRule::sensor_plane) << level.description;
    EXPECT_LT(angle_degrees(level.up, axis), 0.5) << level.description;
    EXPECT_NE(level.description.find("6 of 8 sensors"), std::string::npos) << level.description;
    // Point sensors around the model work the same (their directions from its centre).
    std::vector<pool::Sensor> points = turntable(axis, 5, 30.0);
    for (pool::Sensor& p : points) {
        p.kind = pool::k_sensor_point;
        for (double& v : p.position) v *= 4.0;
    }
    EXPECT_LT(angle_degrees(detect(ball(axis, false), points).up, axis), 0.5);
}

TEST(ScanFrame, WithoutAPlaneOrATurntableUpIsY) {
    const rt::UpDetection d = detect(ball(d3_norm({1, 2, 3}), false));
    EXPECT_EQ(d.rule, rt::UpRule::fallback);
    EXPECT_EQ(d.up, (DVec3{0, 1, 0}));
    EXPECT_LT(d.plane_fraction, 0.2);
    // Sensors bunched within a few degrees of one direction span no plane.
    std::vector<pool::Sensor> s;
    for (const D3& d : {D3{0, 0, 1}, D3{0.05, 0, 1}, D3{0, 0.05, 1}, D3{-0.03, -0.03, 1}}) {
        pool::Sensor x{};
        const D3 u = d3_norm(d);
        for (int k = 0; k < 3; ++k) x.position[k] = u[k];
        x.kind = pool::k_sensor_direction;
        s.push_back(x);
    }
    EXPECT_EQ(detect(ball({0, 1, 0}, false), s).rule, rt::UpRule::fallback);
    EXPECT_EQ(rt::detect_up(rt::UpInput{}).up, (DVec3{0, 1, 0}));
}

/// Image coordinates in [-1, 1] of `p` for a camera (same conventions as core::make_pinhole: the
/// vertical fov, width / height aspect, right = forward x up).
std::array<double, 2> project(const scene::Camera& c, const DVec3& p) {
    const D3 f = d3_norm(d3_sub(c.look_at, c.position));
    const D3 r = d3_norm(cross3(f, c.up));
    const D3 u = cross3(r, f);
    const D3 q = d3_sub(p, c.position);
    const double ty = std::tan(0.5 * c.fov_y_degrees * k_pi / 180.0);
    const double tx = ty * c.width / c.height;
    return {d3_dot(q, r) / d3_dot(q, f) / tx, d3_dot(q, u) / d3_dot(q, f) / ty};
}

TEST(ScanFrame, FramePointsFitsEveryPointTightly) {
    std::vector<DVec3> pts;
    std::uint64_t s = 12345;
    auto rnd = [&]() {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(s >> 11) / 9007199254740992.0;
    };
    for (int i = 0; i < 3000; ++i)
        pts.push_back({3 * rnd() - 1, 0.5 * rnd(), 1.5 * rnd() + 10});  // a flat slab
    for (const auto& [w, h] : {std::pair{512u, 512u}, std::pair{800u, 300u}, std::pair{200u, 600u}}) {
        for (const D3& dir : {D3{0, 0.35, 1}, D3{1, 1, 0.2}, D3{-0.3, 2, -1}}) {
            const scene::Camera c = rt::RenderScene::frame_points(pts, w, h, dir, {0, 1, 0}, 40.0);
            EXPECT_LT(angle_degrees(d3_sub(c.position, c.look_at), dir), 1e-6);
            double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
            for (const DVec3& p : pts) {
                const auto xy = project(c, p);
                for (int a = 0; a < 2; ++a) {
                    lo[a] = std::min(lo[a], xy[a]);
                    hi[a] = std::max(hi[a], xy[a]);
                }
            }
            // Inside with the 5 % border, touching it on one axis, centred on that axis.
            for (int a = 0; a < 2; ++a) {
                EXPECT_GE(lo[a], -1 / 1.05 - 1e-9);
                EXPECT_LE(hi[a], 1 / 1.05 + 1e-9);
            }
            const int tight = hi[0] - lo[0] > hi[1] - lo[1] ? 0 : 1;
            EXPECT_NEAR(hi[tight] - lo[tight], 2 / 1.05, 1e-6) << w << "x" << h;
            EXPECT_NEAR(hi[tight] + lo[tight], 0.0, 1e-6);
        }
    }
}

TEST(ScanFrame, DefaultViewOfAPoolFramesTheModelNotItsOutliers) {
    // A sphere of radius 1 with 5 stray points 200 away: the default camera frames the sphere.
    std::vector<TestPoint> pts = sphere_points({5, -2, 1}, 1.0, 4000);
    for (int i = 0; i < 5; ++i) pts.push_back({{205.0 + i, -2, 1}, {1, 0, 0}, 0.05});
    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {5, -2, 1}))});
    const scene::Camera c = rs.default_camera(256, 256);
    EXPECT_LT(d3_len(d3_sub(c.look_at, {5, -2, 1})), 0.05);
    // The sphere fills the view: its silhouette's angular radius is 1 / 1.05 of the half fov.
    const double dist = d3_len(d3_sub(c.position, c.look_at));
    const double half = 0.5 * c.fov_y_degrees * k_pi / 180.0;
    EXPECT_NEAR(std::tan(std::asin(1.0 / dist)) / std::tan(half), 1 / 1.05, 0.03);
    // The old default: from +z, a little above, +y up (a y-up model seen from its front).
    EXPECT_LT(angle_degrees(d3_sub(c.position, c.look_at), {0, 0.35, 1}), 1e-6);
    EXPECT_EQ(c.up, (DVec3{0, 1, 0}));
    // Another up turns the view: the camera is above the model along it.
    const scene::Camera z = rs.default_camera(256, 256, {0, 0, 1});
    EXPECT_LT(angle_degrees(d3_sub(z.position, z.look_at), {0, -1, 0.35}), 1e-6);
}

/// A closed room: the six faces of the box [-1, 1] x [-0.5, 0.5] x [-1.5, 1.5], 40 x 40 points
/// each, normals inward.
std::vector<TestPoint> closed_room() {
    std::vector<TestPoint> pts;
    const D3 half{1.0, 0.5, 1.5};
    for (int axis = 0; axis < 3; ++axis)
        for (int side = -1; side <= 1; side += 2)
            for (int i = 0; i < 40; ++i)
                for (int j = 0; j < 40; ++j) {
                    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                    D3 p{0, 0, 0}, n{0, 0, 0};
                    p[axis] = side * half[axis];
                    p[u] = half[u] * (-1 + (i + 0.5) / 20.0);
                    p[v] = half[v] * (-1 + (j + 0.5) / 20.0);
                    n[axis] = -side;
                    pts.push_back({p, n, 0.05});
                }
    return pts;
}

bool inside_room(const DVec3& p) {
    return std::fabs(p[0]) < 1.0 && std::fabs(p[1]) < 0.5 && std::fabs(p[2]) < 1.5;
}

TEST(ScanFrame, TheDefaultLightOfACameraInsideAClosedRoomIsInsideIt) {
    // A light outside a closed room is walled off: every shadow ray ends on a wall and the view
    // is unlit. From inside, the default light goes above and right of the camera, inside the
    // room's bounds (the room is convex, so it reaches every wall the camera sees).
    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(make_model(closed_room(), {0, 0, 0}))});
    const struct {
        DVec3 eye, look_at, up;
    } views[] = {{{0.1, -0.2, 0.4}, {-0.5, -0.4, -1.0}, {0, 1, 0}},
                 {{-0.9, 0.45, 1.4}, {0.5, -0.5, -1.5}, {0, 1, 0}},  // close to a corner
                 {{0.3, 0.0, -0.5}, {0.3, 0.0, 1.5}, {1, 0, 0}}};    // another up
    for (const auto& view : views) {
        rs.scene().camera.position = view.eye;
        rs.scene().camera.look_at = view.look_at;
        rs.scene().camera.up = view.up;
        rs.place_default_light();
        ASSERT_EQ(rs.scene().point_lights.size(), 1u);
        const DVec3 light = rs.scene().point_lights[0].position;
        EXPECT_TRUE(inside_room(light)) << light[0] << " " << light[1] << " " << light[2];
        EXPECT_GT(d3_dot(d3_sub(light, view.eye), view.up), 0.0);  // above the camera
    }
    // From outside (the default view), the light stays where it was: 1.5, 3 and 2.5 radii from
    // the look-at point along right, up and back, outside the room.
    rs.scene().camera = rs.default_camera(256, 256);
    rs.place_default_light();
    EXPECT_FALSE(inside_room(rs.scene().point_lights[0].position));
    const rt::Box& b = rs.robust_bounds();
    EXPECT_NEAR(d3_len(d3_sub(rs.scene().point_lights[0].position, rs.scene().camera.look_at)),
                std::sqrt(1.5 * 1.5 + 3.0 * 3.0 + 2.5 * 2.5) * 0.5 * d3_len(d3_sub(b.hi, b.lo)), 1e-9);
}

}  // namespace
}  // namespace prt::test
