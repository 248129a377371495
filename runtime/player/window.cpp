#include "window.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "prt/error.h"
#include "prt/tool.h"

namespace prt::player {

namespace {

struct OrbitState {
    scene::Vec3 target{0, 0, 0};
    double distance = 1, yaw = 0, pitch = 0;  // radians
    bool dragging_left = false, dragging_right = false;
    double last_x = 0, last_y = 0;
    bool dirty = true;
};

scene::Vec3 orbit_position(const OrbitState& o) {
    return {o.target[0] + o.distance * std::cos(o.pitch) * std::sin(o.yaw),
            o.target[1] + o.distance * std::sin(o.pitch),
            o.target[2] + o.distance * std::cos(o.pitch) * std::cos(o.yaw)};
}

struct WindowContext {
    OrbitState orbit;
    std::vector<std::string> backends;
    std::size_t backend_index = 0;
    bool switch_backend = false;
    core::RenderParams* params = nullptr;
    bool quiet = false;
};

void on_key(GLFWwindow* w, int key, int, int action, int) {
    if (action != GLFW_PRESS) return;
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    core::RenderParams& p = *ctx->params;
    switch (key) {
        case GLFW_KEY_ESCAPE:
            glfwSetWindowShouldClose(w, 1);
            break;
        case GLFW_KEY_S:
            p.shadows ^= 1u;
            break;
        case GLFW_KEY_R:
            p.reflections ^= 1u;
            break;
        case GLFW_KEY_T:
            p.refractions ^= 1u;
            break;
        case GLFW_KEY_D:
            p.deep_blending ^= 1u;
            break;
        case GLFW_KEY_K:
            tool::note(ctx->quiet,
                       "prt-play: surface kind: splats (the only surface this build renders; ISO, MLS and "
                       "patches are not implemented yet)");
            break;
        case GLFW_KEY_B:
            if (ctx->backends.size() > 1) {
                ctx->backend_index = (ctx->backend_index + 1) % ctx->backends.size();
                ctx->switch_backend = true;
            }
            break;
        default:
            return;
    }
    ctx->orbit.dirty = true;
}

void on_mouse_button(GLFWwindow* w, int button, int action, int) {
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    glfwGetCursorPos(w, &ctx->orbit.last_x, &ctx->orbit.last_y);
    const bool down = action == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_LEFT) ctx->orbit.dragging_left = down;
    if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE)
        ctx->orbit.dragging_right = down;
}

void on_cursor(GLFWwindow* w, double x, double y) {
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    OrbitState& o = ctx->orbit;
    const double dx = x - o.last_x, dy = y - o.last_y;
    o.last_x = x;
    o.last_y = y;
    if (o.dragging_left) {
        o.yaw -= dx * 0.01;
        o.pitch = std::clamp(o.pitch + dy * 0.01, -1.55, 1.55);
        o.dirty = true;
    } else if (o.dragging_right) {
        // Pan in the camera's image plane, scaled by the distance.
        const double s = o.distance * 0.002;
        const double rx = std::cos(o.yaw), rz = -std::sin(o.yaw);
        const double ux = -std::sin(o.pitch) * std::sin(o.yaw), uy = std::cos(o.pitch),
                     uz = -std::sin(o.pitch) * std::cos(o.yaw);
        o.target[0] += -dx * s * rx + dy * s * ux;
        o.target[1] += dy * s * uy;
        o.target[2] += -dx * s * rz + dy * s * uz;
        o.dirty = true;
    }
}

void on_scroll(GLFWwindow* w, double, double dy) {
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    ctx->orbit.distance *= std::pow(0.9, dy);
    ctx->orbit.dirty = true;
}

}  // namespace

void run_window(rt::RenderScene& rs, std::unique_ptr<rt::Backend>& backend, const WindowOptions& options) {
    if (!glfwInit()) throw Error("cannot initialise GLFW (no display? use --headless)");
    scene::Camera& cam = rs.scene().camera;
    GLFWwindow* window = glfwCreateWindow(static_cast<int>(cam.width), static_cast<int>(cam.height),
                                          "prt-play", nullptr, nullptr);
    if (!window) {
        glfwTerminate();
        throw Error("cannot open a window (no display? use --headless)");
    }
    glfwMakeContextCurrent(window);
    glfwSwapInterval(0);

    WindowContext ctx;
    ctx.quiet = options.quiet;
    ctx.params = &rs.params();
    const rt::BackendAvailability avail = rt::backend_availability();
    ctx.backends = {"cpu"};
    if (avail.cuda_device) {
        ctx.backends.push_back("cuda");
        ctx.backends.push_back("hybrid");
    }
    const auto it = std::find(ctx.backends.begin(), ctx.backends.end(), backend->name());
    ctx.backend_index = it == ctx.backends.end() ? 0 : static_cast<std::size_t>(it - ctx.backends.begin());
    const scene::Vec3 d{cam.position[0] - cam.look_at[0], cam.position[1] - cam.look_at[1],
                        cam.position[2] - cam.look_at[2]};
    ctx.orbit.target = cam.look_at;
    ctx.orbit.distance = std::max(1e-30, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    ctx.orbit.yaw = std::atan2(d[0], d[2]);
    ctx.orbit.pitch = std::asin(std::clamp(d[1] / ctx.orbit.distance, -1.0, 1.0));
    glfwSetWindowUserPointer(window, &ctx);
    glfwSetKeyCallback(window, on_key);
    glfwSetMouseButtonCallback(window, on_mouse_button);
    glfwSetCursorPosCallback(window, on_cursor);
    glfwSetScrollCallback(window, on_scroll);

    GLuint texture = 0;
    glGenTextures(1, &texture);
    glBindTexture(GL_TEXTURE_2D, texture);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    rt::Image image;
    double smoothed_ms = 0;
    while (!glfwWindowShouldClose(window)) {
        glfwPollEvents();
        if (ctx.switch_backend) {
            ctx.switch_backend = false;
            backend = rt::make_backend(ctx.backends[ctx.backend_index], backend_options(options.backend));
            backend->set_scene(rs.view());
        }
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window, &fw, &fh);
        if (fw <= 0 || fh <= 0) continue;
        cam.width = static_cast<std::uint32_t>(fw);
        cam.height = static_cast<std::uint32_t>(fh);
        cam.position = orbit_position(ctx.orbit);
        cam.look_at = ctx.orbit.target;
        rt::FrameRequest req;
        req.camera = rs.camera(cam);
        req.params = rs.params();
        req.width = cam.width;
        req.height = cam.height;
        const rt::FrameStats s = backend->render(req, image);
        const double ms = s.seconds * 1e3;
        smoothed_ms = smoothed_ms > 0 ? 0.9 * smoothed_ms + 0.1 * ms : ms;
        glViewport(0, 0, fw, fh);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, fw, fh, 0, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba8.data());
        glEnable(GL_TEXTURE_2D);
        glBegin(GL_QUADS);  // image row 0 is the top
        glTexCoord2f(0, 1);
        glVertex2f(-1, -1);
        glTexCoord2f(1, 1);
        glVertex2f(1, -1);
        glTexCoord2f(1, 0);
        glVertex2f(1, 1);
        glTexCoord2f(0, 0);
        glVertex2f(-1, 1);
        glEnd();
        glfwSwapBuffers(window);
        const core::RenderParams& p = rs.params();
        char title[256];
        std::snprintf(title, sizeof(title),
                      "prt-play - %s - %.2f ms (%.1f fps) - shadows %s, reflections %s, refractions %s%s",
                      backend->name().c_str(), smoothed_ms, 1e3 / std::max(smoothed_ms, 1e-3),
                      p.shadows ? "on" : "off", p.reflections ? "on" : "off", p.refractions ? "on" : "off",
                      p.deep_blending ? ", deep blending" : "");
        glfwSetWindowTitle(window, title);
    }
    glDeleteTextures(1, &texture);
    glfwDestroyWindow(window);
    glfwTerminate();
}

}  // namespace prt::player
