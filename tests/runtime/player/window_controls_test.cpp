// The window's controls without a window (runtime/player/window_controls.h, label cpu): the key
// table, the view the mouse and fly keys move (checked against the geometry of a camera on +z looking
// at the origin), picking a point of an analytic sphere, numbered names and the camera path a
// recording writes read back by read_camera_path().
#include "window_controls.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>

#include "prt/vec3.h"
#include "test_scene.h"
#include "tool_fixture.h"

namespace prt::test {
namespace {

namespace fs = std::filesystem;
using player::Action;
using player::ViewState;

void expect_near(const scene::Vec3& a, const scene::Vec3& b, double tol) {
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], tol) << "component " << i;
}

scene::Camera camera_on_z() {
    scene::Camera c;
    c.position = {0, 0, 5};
    c.look_at = {0, 0, 0};
    c.up = {0, 1, 0};
    c.fov_y_degrees = 40;
    c.width = 64;
    c.height = 48;
    return c;
}

TEST(WindowControls, EveryActionHasAKeyAndTheFlyKeysNone) {
    std::set<Action> seen;
    for (int key = 0; key < 400; ++key) seen.insert(player::key_action(key));
    for (Action a : {Action::quit, Action::toggle_shadows, Action::toggle_reflections,
                     Action::toggle_refractions, Action::toggle_deep_blending, Action::toggle_path_tracing,
                     Action::next_surface, Action::next_backend, Action::screenshot, Action::reset_view,
                     Action::toggle_recording, Action::print_keys, Action::faster, Action::slower})
        EXPECT_TRUE(seen.count(a)) << "an action without a key: " << int(a);
    for (char c : std::string("WASDQE")) EXPECT_EQ(player::key_action(c), Action::none) << c << " flies";
    EXPECT_EQ(player::key_action('1'), Action::toggle_shadows);
    EXPECT_EQ(player::key_action('P'), Action::toggle_path_tracing);
    EXPECT_EQ(player::key_action('C'), Action::screenshot);
    EXPECT_EQ(player::key_action(player::keys::escape), Action::quit);
    EXPECT_EQ(player::key_code("c"), 'C');
    EXPECT_EQ(player::key_code("Esc"), player::keys::escape);
    EXPECT_EQ(player::key_code("f12"), player::keys::f12);
    EXPECT_EQ(player::key_code("nope"), -1);
    // The printed list names every key the table knows.
    const std::string help = player::key_help();
    for (const char* k :
         {"W A S D", "Q E", "1 2 3 4", " P ", " K ", " B ", "C, F12", "R, Home", " L ", "H, F1", "Esc"})
        EXPECT_NE(help.find(k), std::string::npos) << k;
}

TEST(WindowControls, ViewOfACameraGivesItBack) {
    for (const scene::Vec3 up : {scene::Vec3{0, 1, 0}, scene::Vec3{0, 0, 1}, scene::Vec3{1, 1, 0.3}}) {
        scene::Camera c = camera_on_z();
        c.position = {3, -2, 4};
        c.look_at = {1, 0.5, -1};
        c.up = up;
        const ViewState v = ViewState::from_camera(c);
        expect_near(v.eye(), c.position, 1e-9);
        expect_near(v.target, c.look_at, 0);
        const scene::Camera back = v.apply(c);
        expect_near(back.position, c.position, 1e-9);
        EXPECT_EQ(back.fov_y_degrees, c.fov_y_degrees);
        // forward: from the eye to the target; right and up span the image plane.
        expect_near(v.forward(), normalized(sub(c.look_at, c.position)), 1e-12);
        EXPECT_NEAR(dot(v.right(), v.forward()), 0, 1e-12);
        EXPECT_NEAR(dot(v.up(), v.forward()), 0, 1e-12);
        expect_near(cross(v.right(), v.up()), mul(v.forward(), -1.0), 1e-12);
    }
    // On +z looking at the origin with +y up: right is +x, up +y.
    const ViewState v = ViewState::from_camera(camera_on_z());
    expect_near(v.right(), {1, 0, 0}, 1e-12);
    expect_near(v.up(), {0, 1, 0}, 1e-12);
}

TEST(WindowControls, OrbitPanZoomAndReset) {
    const ViewState start = ViewState::from_camera(camera_on_z());
    ViewState v = start;
    // 157 pixels right: a quarter turn about +y, the target fixed; the eye goes to -x (the scene turns
    // right with the cursor).
    player::orbit(v, 157.079632679, 0);
    expect_near(v.eye(), {-5, 0, 0}, 1e-6);
    expect_near(v.target, {0, 0, 0}, 0);
    // Dragging down lifts the eye; the pitch stops short of the pole.
    player::orbit(v, 0, 1e6);
    EXPECT_GT(v.eye()[1], 4.99);
    EXPECT_LT(v.pitch, 1.5708);
    // Pan: eye and target move together across the view, the scene following the cursor (drag right:
    // the target moves left, 0.002 x distance per pixel).
    v = start;
    player::pan(v, 100, 0);
    expect_near(v.target, {-1, 0, 0}, 1e-12);
    expect_near(v.eye(), {-1, 0, 5}, 1e-12);
    player::pan(v, 0, 50);
    expect_near(v.target, {-1, 0.5, 0}, 1e-12);
    // Zoom: 0.9 per notch toward the target.
    v = start;
    player::zoom(v, 2);
    expect_near(v.eye(), {0, 0, 5 * 0.81}, 1e-12);
    player::zoom(v, -2);
    expect_near(v.eye(), {0, 0, 5}, 1e-12);
}

TEST(WindowControls, FlyMovesEyeAndTargetAtTheSceneSpeed) {
    const ViewState start = ViewState::from_camera(camera_on_z());
    ViewState v = start;
    player::fly_step(v, true, false, false, false, false, false, 2.0, 0.5);  // W: forward, -z
    expect_near(v.eye(), {0, 0, 4}, 1e-12);
    expect_near(v.target, {0, 0, -1}, 1e-12);
    v = start;
    player::fly_step(v, false, false, false, true, false, true, 2.0, 1.0);  // D + E: right and up, normalised
    const double h = 2.0 / std::sqrt(2.0);
    expect_near(v.eye(), {h, h, 5}, 1e-12);
    v = start;
    player::fly_step(v, true, false, true, false, false, false, 2.0, 1.0);  // W + S cancel
    expect_near(v.eye(), start.eye(), 0);
    player::fly_step(v, false, true, false, false, true, false, 1.0, 0.0);  // no time, no move
    expect_near(v.eye(), start.eye(), 0);
    // A quarter of the diagonal per second: a 4 x 0 x 3 box (diagonal 5) is crossed at 1.25 units/s.
    rt::Box b;
    b.lo = {1, 1, 1};
    b.hi = {5, 1, 4};
    b.valid = true;
    EXPECT_DOUBLE_EQ(player::fly_speed(b), 1.25);
    EXPECT_DOUBLE_EQ(player::fly_speed(rt::Box{}), 1.0);
}

TEST(WindowControls, ClickOrDrag) {
    EXPECT_TRUE(player::is_click(10, 10, 12, 7));
    EXPECT_FALSE(player::is_click(10, 10, 14, 10));
    EXPECT_FALSE(player::is_click(10, 10, 10, 5.5));
}

class WindowFilesTest : public FolderTest {
protected:
    WindowFilesTest() : FolderTest("prt_window_controls_test_") {}
};

TEST_F(WindowFilesTest, NumberedNamesSkipFilesThatExist) {
    const std::string pattern = (m_dir / "shot-%04d.png").string();
    EXPECT_EQ(player::next_numbered(pattern), m_dir / "shot-0001.png");
    std::ofstream(m_dir / "shot-0001.png") << "x";
    std::ofstream(m_dir / "shot-0002.png") << "x";
    EXPECT_EQ(player::next_numbered(pattern), m_dir / "shot-0003.png");
}

TEST_F(WindowFilesTest, RecordedPathReadsBackExactly) {
    std::vector<player::CameraKey> keys;
    for (int i = 0; i < 5; ++i) {
        scene::Camera c = camera_on_z();
        c.position = {0.1 * i + 1.0 / 3.0, -2e-7 * i, 5e6 + i};
        c.look_at = {1.0 / 7.0, 2.5, -3.25 * i};
        c.fov_y_degrees = 30 + i / 3.0;
        keys.push_back(player::key_of(c));
    }
    const fs::path file = m_dir / "path.txt";
    player::write_camera_path(file, keys);
    const std::vector<player::CameraKey> back = player::read_camera_path(file);
    ASSERT_EQ(back.size(), keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i) {
        EXPECT_EQ(back[i].position, keys[i].position);
        EXPECT_EQ(back[i].look_at, keys[i].look_at);
        EXPECT_EQ(back[i].fov_y_degrees, keys[i].fov_y_degrees);
        // The replayed camera is the recorded one.
        const scene::Camera c = player::path_camera(camera_on_z(), back, std::uint32_t(i));
        EXPECT_EQ(c.position, keys[i].position);
    }
}

TEST_F(WindowFilesTest, PickReturnsTheWorldHitAndNormalOfTheSphere) {
    // A unit sphere centred at (10, 20, 30) (the render frame is moved: the world position must come
    // back), seen from 5 units along +z.
    const D3 centre{10, 20, 30};
    write_pool(*make_pool(make_model(sphere_points(centre, 1.0, 6000), centre)), m_dir / "ball.pool");
    const rt::RenderScene rs = rt::RenderScene::from_pool(m_dir / "ball.pool");
    scene::Camera cam = camera_on_z();
    cam.position = {10, 20, 35};
    cam.look_at = {10, 20, 30};
    const player::Pick p = player::pick(rs, cam, 32, 24);  // the image centre
    ASSERT_TRUE(p.hit);
    // The front of the sphere: (10, 20, 31), normal +z, 4 units away (splats: within a splat radius).
    expect_near(p.position, {10, 20, 31}, 0.05);
    EXPECT_GT(p.normal[2], 0.99);
    EXPECT_NEAR(p.t, 4.0, 0.05);
    // Off the centre: a point on the sphere whose normal is its direction from the centre.
    const player::Pick q = player::pick(rs, cam, 40.5, 20.25);
    ASSERT_TRUE(q.hit);
    const scene::Vec3 radial = sub(q.position, {10, 20, 30});
    EXPECT_NEAR(length(radial), 1.0, 0.03);
    EXPECT_GT(dot(normalized(radial), q.normal), 0.97);
    EXPECT_GT(q.position[0], 10.0);  // right of the centre in the image: +x
    EXPECT_GT(q.position[1], 20.0);  // above it: +y
    // A corner misses (the sphere fills about 1/4 of the height).
    EXPECT_FALSE(player::pick(rs, cam, 0.5, 0.5).hit);
    EXPECT_NE(player::describe(p, rs, 32, 24).find("position 10"), std::string::npos)
        << player::describe(p, rs, 32, 24);
    EXPECT_NE(player::describe(player::Pick{}, rs, 1, 1).find("nothing hit"), std::string::npos);
}

}  // namespace
}  // namespace prt::test
