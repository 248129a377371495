#include "window_controls.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "prt/atomic_file.h"
#include "prt/core/camera.h"
#include "prt/core/render.h"
#include "prt/error.h"
#include "prt/vec3.h"

namespace prt::player {

Action key_action(int key) {
    switch (key) {
        case keys::escape:
            return Action::quit;
        case '1':
            return Action::toggle_shadows;
        case '2':
            return Action::toggle_reflections;
        case '3':
            return Action::toggle_refractions;
        case '4':
            return Action::toggle_deep_blending;
        case 'P':
            return Action::toggle_path_tracing;
        case 'K':
            return Action::next_surface;
        case 'B':
            return Action::next_backend;
        case 'C':
        case keys::f12:
            return Action::screenshot;
        case 'R':
        case keys::home:
            return Action::reset_view;
        case 'L':
            return Action::toggle_recording;
        case 'H':
        case keys::f1:
            return Action::print_keys;
        case '=':
        case keys::kp_add:
            return Action::faster;
        case '-':
        case keys::kp_subtract:
            return Action::slower;
        default:
            return Action::none;
    }
}

int key_code(const std::string& name) {
    std::string n;
    for (const char c : name) n += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (n.size() == 1 && std::isprint(static_cast<unsigned char>(n[0]))) return n[0];
    if (n == "ESC" || n == "ESCAPE") return keys::escape;
    if (n == "HOME") return keys::home;
    if (n == "F1") return keys::f1;
    if (n == "F12") return keys::f12;
    return -1;
}

std::string key_help() {
    return "prt-play window controls:\n"
           "  left drag          orbit about the look-at point\n"
           "  right/middle drag  pan\n"
           "  wheel              zoom (toward the look-at point)\n"
           "  left click         pick: print the world position and normal of the hit on stdout\n"
           "  W A S D            fly forward, left, back, right (held; speed scales with the scene)\n"
           "  Q E                fly down, up\n"
           "  = / -              fly faster / slower (x 2)\n"
           "  R, Home            reset the view to the starting camera\n"
           "  1 2 3 4            toggle shadows, reflections, refractions, deep blending\n"
           "  P                  toggle path tracing (progressive: samples accumulate while the view "
           "stays still; the title counts them)\n"
           "  K                  next surface the pools hold (splats, iso, mls, patches)\n"
           "  B                  next backend (cpu, cuda, hybrid: those this machine runs)\n"
           "  C, F12             screenshot to the next free prt-play-NNNN image\n"
           "  L                  start / stop recording a camera path (prt-play-path-NNNN.txt; replay "
           "with --camera-path)\n"
           "  H, F1              print this list\n"
           "  Esc                quit\n";
}

ViewState ViewState::from_camera(const scene::Camera& cam) {
    ViewState v;
    // The frame of the camera's up: e1 = k x z (k x -y when k is near z), e2 = e1 x k.
    const double l = length(cam.up);
    v.k = l > 0 ? mul(cam.up, 1.0 / l) : scene::Vec3{0, 1, 0};
    const scene::Vec3 ref = std::fabs(v.k[2]) < 0.9 ? scene::Vec3{0, 0, 1} : scene::Vec3{0, -1, 0};
    v.e1 = normalized(cross(v.k, ref));
    v.e2 = cross(v.e1, v.k);
    const scene::Vec3 d = sub(cam.position, cam.look_at);
    v.target = cam.look_at;
    v.distance = std::max(1e-30, length(d));
    v.yaw = std::atan2(dot(d, v.e1), dot(d, v.e2));
    v.pitch = std::asin(std::clamp(dot(d, v.k) / v.distance, -1.0, 1.0));
    return v;
}

namespace {

/// a e1 + b k + c e2
scene::Vec3 in_frame(const ViewState& v, double a, double b, double c) {
    return add(add(mul(v.e1, a), mul(v.k, b)), mul(v.e2, c));
}

}  // namespace

scene::Vec3 ViewState::eye() const {
    const scene::Vec3 d =
        in_frame(*this, std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
    return add(target, mul(d, distance));
}

scene::Vec3 ViewState::right() const {
    return in_frame(*this, std::cos(yaw), 0, -std::sin(yaw));
}

scene::Vec3 ViewState::up() const {
    return in_frame(*this, -std::sin(pitch) * std::sin(yaw), std::cos(pitch),
                    -std::sin(pitch) * std::cos(yaw));
}

scene::Vec3 ViewState::forward() const {
    return in_frame(*this, -std::cos(pitch) * std::sin(yaw), -std::sin(pitch),
                    -std::cos(pitch) * std::cos(yaw));
}

scene::Camera ViewState::apply(scene::Camera camera) const {
    camera.position = eye();
    camera.look_at = target;
    return camera;
}

void orbit(ViewState& v, double dx, double dy) {
    v.yaw -= dx * 0.01;
    v.pitch = std::clamp(v.pitch + dy * 0.01, -1.55, 1.55);
}

void pan(ViewState& v, double dx, double dy) {
    const double s = v.distance * 0.002;
    v.target = add(v.target, add(mul(v.right(), -dx * s), mul(v.up(), dy * s)));
}

void zoom(ViewState& v, double notches) {
    v.distance = std::max(1e-30, v.distance * std::pow(0.9, notches));
}

void fly_step(ViewState& v, bool w, bool a, bool s, bool d, bool q, bool e, double speed, double seconds) {
    const double f = double(w) - double(s), r = double(d) - double(a), u = double(e) - double(q);
    scene::Vec3 move = add(add(mul(v.forward(), f), mul(v.right(), r)), mul(v.k, u));
    const double l = length(move);
    if (!(l > 0) || !(speed * seconds > 0)) return;
    v.target = add(v.target, mul(move, speed * seconds / l));
}

double fly_speed(const rt::Box& bounds) {
    const double diag = length(sub(bounds.hi, bounds.lo));
    return bounds.valid && std::isfinite(diag) && diag > 0 ? 0.25 * diag : 1.0;
}

Pick pick(const rt::RenderScene& rs, const scene::Camera& camera, double x, double y) {
    Pick p;
    if (camera.width == 0 || camera.height == 0) return p;
    const core::PinholeCamera c = rs.camera(camera);
    // core::primary_ray at a fractional pixel position: the same image-plane mapping.
    const float u = static_cast<float>(x / camera.width), v = static_cast<float>(y / camera.height);
    const core::Vec3 dir = c.forward + c.right * (2.0f * u - 1.0f) + c.up * (1.0f - 2.0f * v);
    const core::Ray ray{c.position, core::normalize(dir), core::k_inf, 0u};
    core::SurfaceHit hit{};
    core::RayCounters counters;
    if (!core::closest_hit_scene(rs.view(), ray, hit, counters)) return p;
    const rt::DVec3& o = rs.render_origin();  // the render frame is the world frame moved by o
    p.hit = true;
    p.position = {o[0] + hit.position.x, o[1] + hit.position.y, o[2] + hit.position.z};
    p.normal = normalized(scene::Vec3{hit.normal.x, hit.normal.y, hit.normal.z});
    p.t = hit.t;
    p.model = hit.model;
    return p;
}

std::string describe(const Pick& p, const rt::RenderScene& rs, double x, double y) {
    char buf[512];
    if (!p.hit) {
        std::snprintf(buf, sizeof buf, "pick: pixel (%.0f, %.0f): nothing hit", x, y);
        return buf;
    }
    const std::string model = p.model < rs.models().size() ? rs.models()[p.model].name : "?";
    std::snprintf(buf, sizeof buf,
                  "pick: pixel (%.0f, %.0f): position %.9g %.9g %.9g, normal %.6f %.6f %.6f, model %s, "
                  "distance %.6g",
                  x, y, p.position[0], p.position[1], p.position[2], p.normal[0], p.normal[1], p.normal[2],
                  model.c_str(), p.t);
    return buf;
}

std::string surfaces_of(const rt::RenderScene& rs) {
    std::string s;
    for (const rt::LoadedModel& m : rs.models())
        s += (s.empty() ? "" : ", ") + m.name + " " + std::string(scene::surface_name(m.view.surface));
    return s;
}

std::optional<rt::RenderScene> next_surface(const rt::RenderScene& rs, const SurfaceReload& reload) {
    if (!reload || rs.models().empty()) return std::nullopt;
    const std::string order[] = {"splats", "iso", "mls", "patches"};
    const std::string current(scene::surface_name(rs.models().front().view.surface));
    int at = 0;
    while (at < 4 && current != order[at]) ++at;
    for (int i = 1; i < 4; ++i) {
        const std::string& name = order[(at + i) % 4];
        try {
            rt::RenderScene next = reload(name);
            const bool all =
                std::all_of(next.models().begin(), next.models().end(), [&](const rt::LoadedModel& m) {
                    return std::string(scene::surface_name(m.view.surface)) == name;
                });
            if (all) return next;  // else a pool without it fell back to another surface
        } catch (const Error&) {
            // this surface's sections are not in every pool: try the next one
        }
    }
    return std::nullopt;
}

bool is_click(double x0, double y0, double x1, double y1) {
    return std::fabs(x1 - x0) <= 3.0 && std::fabs(y1 - y0) <= 3.0;
}

std::filesystem::path next_numbered(const std::string& pattern, std::uint32_t first) {
    for (std::uint32_t n = first; n < first + 1000000u; ++n) {
        char buf[4096];
        std::snprintf(buf, sizeof buf, pattern.c_str(), static_cast<int>(n));
        std::error_code ec;
        if (!std::filesystem::exists(buf, ec)) return buf;
    }
    throw Error(pattern + ": every numbered name is taken");
}

CameraKey key_of(const scene::Camera& camera) {
    return {camera.position, camera.look_at, camera.fov_y_degrees};
}

void write_camera_path(const std::filesystem::path& file, const std::vector<CameraKey>& path) {
    std::ostringstream out;
    out << "# prt-play camera path: px py pz lx ly lz fov_y_degrees (world frame), one frame per line\n";
    char line[512];
    for (const CameraKey& k : path) {
        std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", k.position[0],
                      k.position[1], k.position[2], k.look_at[0], k.look_at[1], k.look_at[2],
                      k.fov_y_degrees);
        out << line;
    }
    write_file_atomic(file, out.str());
}

}  // namespace prt::player
