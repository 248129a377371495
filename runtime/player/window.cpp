#include "window.h"

#include "accumulate.h"

#define GLFW_INCLUDE_GLEXT  // GL 1.5+ buffer-object types and enums (GL_PIXEL_UNPACK_BUFFER)
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "prt/error.h"
#include "prt/runtime/image.h"
#include "prt/tool.h"
#ifdef PRT_HAVE_CUDA_GL
#include "prt/cuda/gl_interop.h"
#endif

namespace prt::player {

namespace {

#ifdef PRT_HAVE_CUDA_GL
/// The GL buffer-object entry points (GL 1.5; pixel buffers GL 2.1), loaded through GLFW: the
/// system libGL need not export them, and the window's legacy context has no loader otherwise.
struct GlBufferApi {
    PFNGLGENBUFFERSPROC gen = nullptr;
    PFNGLBINDBUFFERPROC bind = nullptr;
    PFNGLBUFFERDATAPROC data = nullptr;
    PFNGLDELETEBUFFERSPROC del = nullptr;

    bool load() {
        gen = reinterpret_cast<PFNGLGENBUFFERSPROC>(glfwGetProcAddress("glGenBuffers"));
        bind = reinterpret_cast<PFNGLBINDBUFFERPROC>(glfwGetProcAddress("glBindBuffer"));
        data = reinterpret_cast<PFNGLBUFFERDATAPROC>(glfwGetProcAddress("glBufferData"));
        del = reinterpret_cast<PFNGLDELETEBUFFERSPROC>(glfwGetProcAddress("glDeleteBuffers"));
        return gen && bind && data && del;
    }
};
#endif

/// How a frame reaches the window: a texture drawn over the whole framebuffer, filled either by
/// an upload of the rendered image from host memory (CPU and hybrid backends, and the fallback),
/// or, with the CUDA backend, from a pixel buffer the kernels wrote through CUDA-OpenGL interop
/// (map, render into it, unmap, glTexSubImage2D from the bound PBO: the frame stays on the GPU).
class FrameDisplay {
public:
    FrameDisplay(bool quiet, bool interop) : m_quiet(quiet), m_interop_allowed(interop) {
        glGenTextures(1, &m_texture);
        glBindTexture(GL_TEXTURE_2D, m_texture);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);  // RGBA8 rows are whole words
    }
    ~FrameDisplay() {
#ifdef PRT_HAVE_CUDA_GL
        release_interop();
#endif
        glDeleteTextures(1, &m_texture);
    }
    FrameDisplay(const FrameDisplay&) = delete;
    FrameDisplay& operator=(const FrameDisplay&) = delete;

    /// Renders `req` (fw x fh) with `backend` and draws it over the whole framebuffer; with `acc`,
    /// the frame joins the running mean first (sampled frames: host memory, no interop).
    rt::FrameStats render(rt::Backend& backend, rt::FrameRequest req, rt::Image& image, int fw, int fh,
                          Accumulator* acc = nullptr) {
        if (fw != m_tex_w || fh != m_tex_h) {  // (re)allocate the texture for the framebuffer size
            glBindTexture(GL_TEXTURE_2D, m_texture);
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, fw, fh, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
            m_tex_w = fw;
            m_tex_h = fh;
        }
        glBindTexture(GL_TEXTURE_2D, m_texture);
        rt::FrameStats stats;
        bool shown = false;
#ifdef PRT_HAVE_CUDA_GL
        if (acc == nullptr && backend.name() == "cuda" && m_interop_allowed && !m_interop_failed) {
            shown = render_interop(backend, req, image, fw, fh, stats);
        }
#endif
        if (!shown) {
            stats = backend.render(req, image);
            if (acc != nullptr) acc->add(image, req.params);
            glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba8.data());
        }
        glViewport(0, 0, fw, fh);
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
        return stats;
    }

    /// "interop" while frames go through the pixel buffer, else "texture upload".
    const char* path() const {
        return m_interop_active ? "interop" : "texture upload";
    }

private:
#ifdef PRT_HAVE_CUDA_GL
    /// One frame through the registered pixel buffer; false (and the texture upload from then on)
    /// when the buffer cannot be created, registered or mapped.
    bool render_interop(rt::Backend& backend, rt::FrameRequest req, rt::Image& image, int fw, int fh,
                        rt::FrameStats& stats) {
        const std::size_t need = static_cast<std::size_t>(fw) * static_cast<std::size_t>(fh) * 4;
        void* pixels = nullptr;
        try {
            if (fw != m_pbo_w || fh != m_pbo_h || !m_registered) {
                release_interop();
                if (!m_gl.gen && !m_gl.load()) throw Error("the GL context has no buffer objects (GL 2.1)");
                m_gl.gen(1, &m_pbo);
                m_gl.bind(GL_PIXEL_UNPACK_BUFFER, m_pbo);
                m_gl.data(GL_PIXEL_UNPACK_BUFFER, static_cast<GLsizeiptr>(need), nullptr, GL_STREAM_DRAW);
                m_gl.bind(GL_PIXEL_UNPACK_BUFFER, 0);
                m_registered.emplace(m_pbo);
                m_pbo_w = fw;
                m_pbo_h = fh;
            }
            std::size_t bytes = 0;
            pixels = m_registered->map(bytes);
            if (bytes < need) throw Error("the mapped pixel buffer is smaller than the frame");
        } catch (const Error& e) {
            if (pixels) m_registered->unmap();
            release_interop();
            m_interop_failed = true;
            m_interop_active = false;
            tool::note(m_quiet,
                       "prt-play: CUDA-OpenGL interop unavailable (%s): frames go through a texture upload",
                       e.what());
            return false;
        }
        req.device_rgba8 = pixels;
        req.download = false;
        try {
            stats = backend.render(req, image);
        } catch (...) {
            m_registered->unmap();
            throw;
        }
        m_registered->unmap();
        m_gl.bind(GL_PIXEL_UNPACK_BUFFER, m_pbo);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);  // from the PBO
        m_gl.bind(GL_PIXEL_UNPACK_BUFFER, 0);
        if (!m_interop_active)
            tool::note(m_quiet, "prt-play: frames reach the window through CUDA-OpenGL interop");
        m_interop_active = true;
        return true;
    }

    void release_interop() {
        m_registered.reset();  // unregister before the buffer is deleted
        if (m_pbo) m_gl.del(1, &m_pbo);
        m_pbo = 0;
        m_pbo_w = m_pbo_h = 0;
    }

    GlBufferApi m_gl;
    GLuint m_pbo = 0;
    int m_pbo_w = 0, m_pbo_h = 0;
    std::optional<cuda::GlPixelBuffer> m_registered;
#endif
    GLuint m_texture = 0;
    int m_tex_w = 0, m_tex_h = 0;
    bool m_quiet;
    bool m_interop_allowed;
    bool m_interop_failed = false;
    bool m_interop_active = false;
};

/// The last GLFW error, for one-line messages.
std::string g_glfw_error = "no GLFW error reported";
void on_glfw_error(int code, const char* text) {
    g_glfw_error = "GLFW error " + std::to_string(code) + ": " + (text ? text : "?");
}

/// Destroys the window and terminates GLFW on every way out of run_window().
struct WindowGuard {
    GLFWwindow* window = nullptr;
    WindowGuard() = default;
    WindowGuard(const WindowGuard&) = delete;
    WindowGuard& operator=(const WindowGuard&) = delete;
    ~WindowGuard() {
        if (window) glfwDestroyWindow(window);
        glfwTerminate();
    }
};

/// Reads the framebuffer just drawn (the back buffer, before the swap) and writes it as an 8-bit
/// image: GL rows run bottom-up, image rows top-down.
void write_screenshot(const std::filesystem::path& path, int fw, int fh) {
    rt::Image shot;
    shot.resize(static_cast<std::uint32_t>(fw), static_cast<std::uint32_t>(fh));
    std::vector<std::uint32_t> rows(shot.rgba8.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
    const GLenum err = glGetError();
    if (err != GL_NO_ERROR)
        throw Error(path.string() + ": glReadPixels failed (GL error " + std::to_string(err) + ")");
    const std::size_t w = static_cast<std::size_t>(fw);
    for (int y = 0; y < fh; ++y) {
        const std::uint32_t* src = rows.data() + static_cast<std::size_t>(fh - 1 - y) * w;
        std::uint32_t* dst = shot.rgba8.data() + static_cast<std::size_t>(y) * w;
        for (std::size_t x = 0; x < w; ++x) {
            const std::uint32_t p = src[x] | 0xff000000u;  // R in the low byte, as Image::rgba8
            dst[x] = p;
            float* rgb = shot.rgb.data() + (static_cast<std::size_t>(y) * w + x) * 3;
            for (int c = 0; c < 3; ++c) rgb[c] = static_cast<float>((p >> (8 * c)) & 0xffu) / 255.0f;
        }
    }
    rt::write_image(path, shot);
}

/// The orbit about the look-at point, in a frame of the camera's up k: e1, k, e2 right-handed
/// (for +y up: x, y, z). Yaw turns about k from e2 toward e1; pitch lifts toward k.
struct OrbitState {
    scene::Vec3 target{0, 0, 0};
    double distance = 1, yaw = 0, pitch = 0;  // radians
    scene::Vec3 e1{1, 0, 0}, k{0, 1, 0}, e2{0, 0, 1};
    bool dragging_left = false, dragging_right = false;
    double last_x = 0, last_y = 0;
    bool dirty = true;

    /// The frame of an up direction: e1 = k x z (k x -y when k is near z), e2 = e1 x k.
    void set_up(const scene::Vec3& up) {
        const double l = std::sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
        k = l > 0 ? scene::Vec3{up[0] / l, up[1] / l, up[2] / l} : scene::Vec3{0, 1, 0};
        const scene::Vec3 ref = std::fabs(k[2]) < 0.9 ? scene::Vec3{0, 0, 1} : scene::Vec3{0, -1, 0};
        e1 = cross(k, ref);
        const double el = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
        for (double& c : e1) c /= el;
        e2 = cross(e1, k);
    }
    static scene::Vec3 cross(const scene::Vec3& a, const scene::Vec3& b) {
        return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    }
    /// a e1 + b k + c e2
    scene::Vec3 in_frame(double a, double b, double c) const {
        return {a * e1[0] + b * k[0] + c * e2[0], a * e1[1] + b * k[1] + c * e2[1],
                a * e1[2] + b * k[2] + c * e2[2]};
    }
};

scene::Vec3 orbit_position(const OrbitState& o) {
    const scene::Vec3 d = o.in_frame(std::cos(o.pitch) * std::sin(o.yaw), std::sin(o.pitch),
                                     std::cos(o.pitch) * std::cos(o.yaw));
    return {o.target[0] + o.distance * d[0], o.target[1] + o.distance * d[1],
            o.target[2] + o.distance * d[2]};
}

struct WindowContext {
    OrbitState orbit;
    std::vector<std::string> backends;
    std::size_t backend_index = 0;
    bool switch_backend = false;
    core::RenderParams* params = nullptr;
    bool quiet = false;
    std::string surfaces;  ///< "model: surface" of every model (key K)
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
            tool::note(ctx->quiet, "prt-play: surfaces: %s", ctx->surfaces.c_str());
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
        const scene::Vec3 right = o.in_frame(std::cos(o.yaw), 0, -std::sin(o.yaw));
        const scene::Vec3 up = o.in_frame(-std::sin(o.pitch) * std::sin(o.yaw), std::cos(o.pitch),
                                          -std::sin(o.pitch) * std::cos(o.yaw));
        for (int i = 0; i < 3; ++i) o.target[i] += -dx * s * right[i] + dy * s * up[i];
        o.dirty = true;
    }
}

void on_scroll(GLFWwindow* w, double, double dy) {
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    ctx->orbit.distance *= std::pow(0.9, dy);
    ctx->orbit.dirty = true;
}

}  // namespace

void run_window(rt::RenderScene& rs, std::unique_ptr<rt::Backend>& backend,
                std::unique_ptr<rt::BrickStream>& stream, const WindowOptions& options) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) throw Error("cannot initialise GLFW (" + g_glfw_error + "; no display? use --headless)");
    WindowGuard guard;  // destroyed last: after the display's GL objects
    scene::Camera& cam = rs.scene().camera;
    guard.window = glfwCreateWindow(static_cast<int>(cam.width), static_cast<int>(cam.height), "prt-play",
                                    nullptr, nullptr);
    GLFWwindow* window = guard.window;
    if (!window) throw Error("cannot open a window (" + g_glfw_error + "; no display? use --headless)");
    glfwMakeContextCurrent(window);
    glfwSwapInterval(0);

    WindowContext ctx;
    ctx.quiet = options.quiet;
    ctx.params = &rs.params();
    for (const rt::LoadedModel& m : rs.models())
        ctx.surfaces += (ctx.surfaces.empty() ? "" : ", ") + m.name + " " +
                        std::string(scene::surface_name(m.view.surface));
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
    ctx.orbit.set_up(cam.up);  // the orbit turns about the camera's up (--up, a scene's camera.up)
    ctx.orbit.distance = std::max(1e-30, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    auto along = [&](const scene::Vec3& e) { return d[0] * e[0] + d[1] * e[1] + d[2] * e[2]; };
    ctx.orbit.yaw = std::atan2(along(ctx.orbit.e1), along(ctx.orbit.e2));
    ctx.orbit.pitch = std::asin(std::clamp(along(ctx.orbit.k) / ctx.orbit.distance, -1.0, 1.0));
    glfwSetWindowUserPointer(window, &ctx);
    glfwSetKeyCallback(window, on_key);
    glfwSetMouseButtonCallback(window, on_mouse_button);
    glfwSetCursorPosCallback(window, on_cursor);
    glfwSetScrollCallback(window, on_scroll);

    FrameDisplay display(options.quiet, options.interop);
    rt::Image image;
    Accumulator acc;  // sampled frames (path tracing, spp > 1) converge while the view stays still
    core::PinholeCamera last_camera{};
    double smoothed_ms = 0;
    std::uint32_t shown = 0;
    const std::uint32_t frames = options.screenshot.empty() ? options.frames : std::max(options.frames, 1u);
    while (!glfwWindowShouldClose(window)) {
        glfwPollEvents();
        if (ctx.switch_backend) {
            ctx.switch_backend = false;
            stream.reset();  // its storage belongs to the old backend
            backend = rt::make_backend(ctx.backends[ctx.backend_index], backend_options(options.backend));
            stream =
                std::make_unique<rt::BrickStream>(rs, *backend, stream_options(options.backend, *backend));
            acc.reset();
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
        const bool sampled = req.params.path_tracing != 0 || req.params.spp > 1;
        if (std::memcmp(&req.camera, &last_camera, sizeof(last_camera)) != 0) acc.reset();
        last_camera = req.camera;
        req.params.frame = acc.frames();
        const rt::FrameStats s = display.render(*backend, req, image, fw, fh, sampled ? &acc : nullptr);
        ++shown;
        // Streaming: the bricks this frame asked for are there for the next one (progressive).
        const rt::StreamFrame sf = stream->after_frame(s);
        if (sf.streaming && sf.uploaded > 0)
            tool::note(options.quiet, "prt-play: frame %u: %s", shown, rt::describe(sf).c_str());
        if (sf.streaming && sf.fallback_rays > 0) acc.reset();  // the image is still refining
        const bool last = frames > 0 && shown >= frames;
        if (last && !options.screenshot.empty()) {
            write_screenshot(options.screenshot, fw, fh);
            tool::note(options.quiet,
                       "prt-play: wrote %s (%dx%d, the window's framebuffer after %u frames, %s)",
                       options.screenshot.string().c_str(), fw, fh, shown, display.path());
        }
        glfwSwapBuffers(window);
        const double ms = s.seconds * 1e3;
        smoothed_ms = smoothed_ms > 0 ? 0.9 * smoothed_ms + 0.1 * ms : ms;
        const core::RenderParams& p = rs.params();
        char streaming[128] = "";
        if (sf.streaming)
            std::snprintf(streaming, sizeof(streaming), " - bricks %u/%u resident, %llu rays coarse",
                          sf.resident_bricks, sf.brick_count,
                          static_cast<unsigned long long>(sf.fallback_rays));
        char title[384];
        std::snprintf(
            title, sizeof(title),
            "prt-play - %s (%s) - %.2f ms (%.1f fps) - shadows %s, reflections %s, refractions %s%s%s",
            backend->name().c_str(), display.path(), smoothed_ms, 1e3 / std::max(smoothed_ms, 1e-3),
            p.shadows ? "on" : "off", p.reflections ? "on" : "off", p.refractions ? "on" : "off",
            p.deep_blending ? ", deep blending" : "", streaming);
        glfwSetWindowTitle(window, title);
        if (last) break;
    }
}

}  // namespace prt::player
