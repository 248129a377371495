// PointRT player: what the window's keys and mouse do, without a window (so that it is tested
// without one, tests/runtime/player): the key -> action table and its printed list, the view the
// mouse and the fly keys move (an orbit about a look-at point), picking a point, numbered output
// names and the camera path a recording writes (camera_path.h reads it back).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "camera_path.h"
#include "prt/formats/scene.h"
#include "prt/runtime/render_scene.h"

namespace prt::player {

/// Key codes as GLFW numbers them: printable keys are their ASCII upper case ('A', '1', '='),
/// the others these (window.cpp checks them against GLFW's constants).
namespace keys {
inline constexpr int escape = 256, home = 268, f1 = 290, f12 = 301, kp_add = 334, kp_subtract = 333;
}  // namespace keys

/// What a key press does in the window.
enum class Action {
    none,
    quit,                  ///< Esc
    toggle_shadows,        ///< 1
    toggle_reflections,    ///< 2
    toggle_refractions,    ///< 3
    toggle_deep_blending,  ///< 4
    toggle_path_tracing,   ///< P: progressive path tracing (seed 002, 7)
    next_surface,          ///< K: the next surface the models' pools hold
    next_backend,          ///< B: cpu / cuda / hybrid, those this machine runs
    screenshot,            ///< C or F12: the framebuffer to the next numbered file
    reset_view,            ///< R or Home: the camera the window opened with
    toggle_recording,      ///< L: start / stop recording a camera path
    print_keys,            ///< H or F1: this list on stdout
    faster,                ///< = or keypad +: fly speed x 2
    slower,                ///< - or keypad -: fly speed / 2
};

/// The action of a key press (GLFW key code); W, A, S, D, Q, E fly while held (fly_step) and
/// have no press action.
Action key_action(int key);
/// A key the "--keys" option names ("C", "1", "Esc", "F12", "Home"), or -1 when unknown.
int key_code(const std::string& name);
/// The printed list of window controls (mouse, fly keys, key actions), one per line.
std::string key_help();

/// The view the window shows: an orbit about `target` at `distance`, in a frame of the camera's
/// up k (e1, k, e2 right-handed: for +y up x, y, z). Yaw turns about k from e2 toward e1, pitch
/// lifts toward k (clamped short of the poles).
struct ViewState {
    scene::Vec3 target{0, 0, 0};
    double distance = 1, yaw = 0, pitch = 0;  ///< radians
    scene::Vec3 e1{1, 0, 0}, k{0, 1, 0}, e2{0, 0, 1};

    /// The view of a camera: its look-at point, distance and direction about its up.
    static ViewState from_camera(const scene::Camera& camera);
    /// The eye position.
    scene::Vec3 eye() const;
    /// Unit vectors of the image plane: toward the right of the image, toward its top, and the
    /// viewing direction (from the eye to the target).
    scene::Vec3 right() const;
    scene::Vec3 up() const;
    scene::Vec3 forward() const;
    /// `camera` with this view's eye and look-at point (size, fov and up kept).
    scene::Camera apply(scene::Camera camera) const;
};

/// Left drag: turns the view about its target, 0.01 radian per pixel (drag right: the scene turns
/// right; drag down: the eye rises).
void orbit(ViewState& v, double dx_pixels, double dy_pixels);
/// Right or middle drag: moves the target and eye together in the image plane so the scene follows
/// the cursor, 0.002 x distance per pixel.
void pan(ViewState& v, double dx_pixels, double dy_pixels);
/// Mouse wheel: distance x 0.9 per notch toward the target (negative notches move away).
void zoom(ViewState& v, double notches);
/// Fly keys held for `seconds`: moves the eye and target together by speed x seconds along
/// forward (W +, S -), right (D +, A -) and the camera's up k (E +, Q -); diagonal moves are
/// normalised so they are not faster.
void fly_step(ViewState& v, bool w, bool a, bool s, bool d, bool q, bool e, double speed, double seconds);
/// The fly speed of a scene: a quarter of the diagonal of its robust bounds per second (a room
/// crossed in a few seconds, whatever its units); 1 for an empty or degenerate box.
double fly_speed(const rt::Box& bounds);

/// What a click picked: the closest hit of the ray through a pixel, in the world frame.
struct Pick {
    bool hit = false;
    scene::Vec3 position{0, 0, 0};  ///< world
    scene::Vec3 normal{0, 0, 1};    ///< unit, outward as stored
    double t = 0;                   ///< distance from the eye
    std::uint32_t model = 0;        ///< index into RenderScene::models()
};
/// Casts the primary ray of pixel (x, y) (row 0 at the top; fractional positions allowed) of
/// `camera` into the host scene view (core::closest_hit_scene, the CPU backend's traversal).
Pick pick(const rt::RenderScene& scene, const scene::Camera& camera, double x, double y);
/// One line for stdout: "pick: pixel (X, Y): position ..., normal ..., model NAME, distance T" or
/// "pick: pixel (X, Y): nothing hit".
std::string describe(const Pick& p, const rt::RenderScene& scene, double x, double y);

/// Loads a scene again with every model as one surface (LoadOptions::surface); throws prt::Error
/// when a pool lacks it.
using SurfaceReload = std::function<rt::RenderScene(const std::string& surface)>;
/// K: the scene reloaded as the next surface after the first model's, in the order splats, iso, mls,
/// patches (cycling), that every model's pool holds; nullopt when no other one loads. The caller
/// keeps its camera and render settings.
std::optional<rt::RenderScene> next_surface(const rt::RenderScene& scene, const SurfaceReload& reload);
/// "name surface, ..." of the models.
std::string surfaces_of(const rt::RenderScene& scene);

/// A press and release this close (pixels, each axis) is a click (pick), farther a drag.
bool is_click(double x0, double y0, double x1, double y1);

/// `pattern` with a printf field (prt-play-%04d.png) filled with the first number from `first` on
/// whose file does not exist yet.
std::filesystem::path next_numbered(const std::string& pattern, std::uint32_t first = 1);

/// The key of a camera (its position, look-at point and vertical fov).
CameraKey key_of(const scene::Camera& camera);
/// Writes keys in the format read_camera_path() reads ("px py pz lx ly lz fov" per line, full
/// precision, after a comment line), atomically.
void write_camera_path(const std::filesystem::path& file, const std::vector<CameraKey>& keys);

}  // namespace prt::player
