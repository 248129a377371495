#include "window.h"

#include "accumulate.h"
#include "window_controls.h"

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

static_assert(keys::escape == GLFW_KEY_ESCAPE && keys::home == GLFW_KEY_HOME && keys::f1 == GLFW_KEY_F1 &&
                  keys::f12 == GLFW_KEY_F12 && keys::kp_add == GLFW_KEY_KP_ADD &&
                  keys::kp_subtract == GLFW_KEY_KP_SUBTRACT && GLFW_KEY_A == 'A' && GLFW_KEY_1 == '1' &&
                  GLFW_KEY_EQUAL == '=' && GLFW_KEY_MINUS == '-',
              "window_controls.h key codes are GLFW's");

/// The window's state between callbacks: the view the mouse and fly keys move (window_controls.h)
/// and the requests the keys and clicks leave for the render loop.
struct WindowContext {
    ViewState view, start_view;  ///< start_view: reset (R, Home)
    bool dragging_left = false, dragging_right = false;
    bool drag_moved = false;  ///< the left button left the click zone since it was pressed
    double last_x = 0, last_y = 0, press_x = 0, press_y = 0;
    bool dirty = true;
    double fly_speed = 1;  ///< world units per second
    std::vector<std::string> backends;
    std::size_t backend_index = 0;
    bool switch_backend = false;
    bool next_surface = false;
    bool screenshot = false;
    bool toggle_recording = false;
    std::vector<std::pair<double, double>> picks;  ///< clicks (window coordinates) not yet picked
    core::RenderParams* params = nullptr;
    bool quiet = false;
};

/// What a key press does (the window's key callback and --keys).
void apply_action(GLFWwindow* w, WindowContext& ctx, Action a) {
    core::RenderParams& p = *ctx.params;
    switch (a) {
        case Action::none:
            return;
        case Action::quit:
            glfwSetWindowShouldClose(w, 1);
            break;
        case Action::toggle_shadows:
            p.shadows ^= 1u;
            break;
        case Action::toggle_reflections:
            p.reflections ^= 1u;
            break;
        case Action::toggle_refractions:
            p.refractions ^= 1u;
            break;
        case Action::toggle_deep_blending:
            p.deep_blending ^= 1u;
            break;
        case Action::toggle_path_tracing:
            p.path_tracing ^= 1u;
            break;
        case Action::next_surface:
            ctx.next_surface = true;
            break;
        case Action::next_backend:
            if (ctx.backends.size() > 1) {
                ctx.backend_index = (ctx.backend_index + 1) % ctx.backends.size();
                ctx.switch_backend = true;
            } else {
                tool::note(ctx.quiet, "prt-play: only the cpu backend runs on this machine");
            }
            break;
        case Action::screenshot:
            ctx.screenshot = true;
            break;
        case Action::reset_view:
            ctx.view = ctx.start_view;
            break;
        case Action::toggle_recording:
            ctx.toggle_recording = true;
            break;
        case Action::print_keys:
            std::fputs(key_help().c_str(), stdout);
            std::fflush(stdout);
            break;
        case Action::faster:
            ctx.fly_speed *= 2;
            tool::note(ctx.quiet, "prt-play: fly speed %.4g units/s", ctx.fly_speed);
            break;
        case Action::slower:
            ctx.fly_speed *= 0.5;
            tool::note(ctx.quiet, "prt-play: fly speed %.4g units/s", ctx.fly_speed);
            break;
    }
    ctx.dirty = true;
}

void on_key(GLFWwindow* w, int key, int, int action, int) {
    if (action != GLFW_PRESS) return;
    apply_action(w, *static_cast<WindowContext*>(glfwGetWindowUserPointer(w)), key_action(key));
}

void on_mouse_button(GLFWwindow* w, int button, int action, int) {
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    double x = 0, y = 0;
    glfwGetCursorPos(w, &x, &y);
    ctx->last_x = x;
    ctx->last_y = y;
    const bool down = action == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        ctx->dragging_left = down;
        if (down) {
            ctx->press_x = x;
            ctx->press_y = y;
            ctx->drag_moved = false;
        } else if (!ctx->drag_moved && is_click(ctx->press_x, ctx->press_y, x, y)) {
            ctx->picks.emplace_back(x, y);
        }
    }
    if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) ctx->dragging_right = down;
}

void on_cursor(GLFWwindow* w, double x, double y) {
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    const double dx = x - ctx->last_x, dy = y - ctx->last_y;
    ctx->last_x = x;
    ctx->last_y = y;
    if (ctx->dragging_left && !is_click(ctx->press_x, ctx->press_y, x, y)) ctx->drag_moved = true;
    if (ctx->dragging_left && ctx->drag_moved) {
        orbit(ctx->view, dx, dy);
        ctx->dirty = true;
    } else if (ctx->dragging_right) {
        pan(ctx->view, dx, dy);
        ctx->dirty = true;
    }
}

void on_scroll(GLFWwindow* w, double, double dy) {
    auto* ctx = static_cast<WindowContext*>(glfwGetWindowUserPointer(w));
    zoom(ctx->view, dy);
    ctx->dirty = true;
}

/// K: the scene reloaded as the next surface its pools hold (window_controls.h next_surface), the
/// camera and render settings kept. False (and a note) when none other loads.
bool cycle_surface(rt::RenderScene& rs, const WindowOptions& options) {
    if (!options.reload) {
        tool::note(options.quiet, "prt-play: this scene cannot switch surfaces");
        return false;
    }
    std::optional<rt::RenderScene> next = next_surface(rs, options.reload);
    if (!next) {
        tool::note(options.quiet, "prt-play: no other surface in the pools (%s)", surfaces_of(rs).c_str());
        return false;
    }
    const scene::Camera cam = rs.scene().camera;
    const core::RenderParams params = rs.params();
    rs = std::move(*next);
    rs.scene().camera = cam;
    rs.params() = params;
    tool::note(options.quiet, "prt-play: surfaces now: %s", surfaces_of(rs).c_str());
    return true;
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
    const rt::BackendAvailability avail = rt::backend_availability();
    ctx.backends = {"cpu"};
    if (avail.cuda_device) {
        ctx.backends.push_back("cuda");
        ctx.backends.push_back("hybrid");
    }
    const auto it = std::find(ctx.backends.begin(), ctx.backends.end(), backend->name());
    ctx.backend_index = it == ctx.backends.end() ? 0 : static_cast<std::size_t>(it - ctx.backends.begin());
    ctx.view = ctx.start_view = ViewState::from_camera(cam);  // turns about the camera's up
    ctx.fly_speed = fly_speed(rs.robust_bounds());
    glfwSetWindowUserPointer(window, &ctx);
    glfwSetKeyCallback(window, on_key);
    glfwSetMouseButtonCallback(window, on_mouse_button);
    glfwSetCursorPosCallback(window, on_cursor);
    glfwSetScrollCallback(window, on_scroll);
    tool::note(options.quiet,
               "prt-play: window controls: press H (or run prt-play --help-keys) for the list");

    FrameDisplay display(options.quiet, options.interop);
    rt::Image image;
    Accumulator acc;  // sampled frames (path tracing, spp > 1) converge while the view stays still
    core::PinholeCamera last_camera{};
    core::RenderParams last_params{};
    double smoothed_ms = 0, last_time = tool::now_seconds();
    std::uint32_t shown = 0;
    std::size_t next_key = 0;  ///< --keys: the next scripted key (one before each frame)
    bool recording = false;
    std::vector<CameraKey> recorded;
    const auto save_recording = [&] {
        std::filesystem::path file;
        try {
            file = next_numbered(options.save_prefix + "-path-%04d.txt");
            write_camera_path(file, recorded);
        } catch (const Error& e) {
            std::fprintf(stderr, "prt-play: camera path not written: %s\n", e.what());
            return;
        }
        tool::note(options.quiet,
                   "prt-play: recorded %zu frames to %s (replay headless: prt-play ... --camera-path %s "
                   "--frames %zu --out 'frame_%%04d.png')",
                   recorded.size(), file.string().c_str(), file.string().c_str(), recorded.size());
    };
    const std::string image_ext = rt::have_oiio() ? ".png" : ".ppm";
    // --frames: the window's own speed, said at the end (frame-to-frame time: render, display, swap).
    std::vector<double> loop_ms, render_ms;
    double loop_start = 0;
    const std::uint32_t frames = options.screenshot.empty() ? options.frames : std::max(options.frames, 1u);
    while (!glfwWindowShouldClose(window)) {
        glfwPollEvents();
        if (next_key < options.keys.size() && next_key <= shown)
            apply_action(window, ctx, key_action(options.keys[next_key++]));
        if (ctx.next_surface) {
            ctx.next_surface = false;
            stream.reset();  // it holds the old scene's bricks
            if (cycle_surface(rs, options)) {
                backend = rt::make_backend(ctx.backends[ctx.backend_index], backend_options(options.backend));
                ctx.switch_backend = false;
            }
            stream =
                std::make_unique<rt::BrickStream>(rs, *backend, stream_options(options.backend, *backend));
            acc.reset();
        }
        if (ctx.switch_backend) {
            ctx.switch_backend = false;
            stream.reset();  // its storage belongs to the old backend
            backend = rt::make_backend(ctx.backends[ctx.backend_index], backend_options(options.backend));
            stream =
                std::make_unique<rt::BrickStream>(rs, *backend, stream_options(options.backend, *backend));
            acc.reset();
        }
        // Fly keys held: a move of speed x the time since the last frame (at most 0.1 s of it).
        const double now = tool::now_seconds();
        const double dt = std::min(0.1, now - last_time);
        last_time = now;
        const auto held = [&](int key) { return glfwGetKey(window, key) == GLFW_PRESS; };
        const bool w = held(GLFW_KEY_W), a = held(GLFW_KEY_A), s_key = held(GLFW_KEY_S), d = held(GLFW_KEY_D),
                   q = held(GLFW_KEY_Q), e = held(GLFW_KEY_E);
        if (w || a || s_key || d || q || e) fly_step(ctx.view, w, a, s_key, d, q, e, ctx.fly_speed, dt);
        if (ctx.toggle_recording) {
            ctx.toggle_recording = false;
            recording = !recording;
            if (recording) {
                recorded.clear();
                tool::note(options.quiet, "prt-play: recording the camera path (L stops)");
            } else if (!recorded.empty()) {
                save_recording();
            }
        }
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window, &fw, &fh);
        if (fw <= 0 || fh <= 0) continue;
        cam.width = static_cast<std::uint32_t>(fw);
        cam.height = static_cast<std::uint32_t>(fh);
        cam = ctx.view.apply(cam);
        if (recording) recorded.push_back(key_of(cam));
        rt::FrameRequest req;
        req.camera = rs.camera(cam);
        req.params = rs.params();
        req.width = cam.width;
        req.height = cam.height;
        const bool sampled = req.params.path_tracing != 0 || req.params.spp > 1;
        if (std::memcmp(&req.camera, &last_camera, sizeof(last_camera)) != 0 ||
            std::memcmp(&req.params, &last_params, sizeof(last_params)) != 0)
            acc.reset();  // the view or a setting changed: start the mean again
        last_camera = req.camera;
        last_params = req.params;
        req.params.frame = acc.frames();
        const rt::FrameStats s = display.render(*backend, req, image, fw, fh, sampled ? &acc : nullptr);
        ++shown;
        // Clicks: the hit under the cursor, on the host view (the CPU backend's traversal).
        if (!ctx.picks.empty()) {
            int ww = 0, wh = 0;
            glfwGetWindowSize(window, &ww, &wh);
            for (const auto& [x, y] : ctx.picks) {
                const double px = ww > 0 ? x * fw / ww : x, py = wh > 0 ? y * fh / wh : y;
                if (stream->streaming() && backend->name() != "cpu") {
                    std::printf("pick: pixel (%.0f, %.0f): not available while bricks stream to the GPU\n",
                                px, py);
                } else {
                    std::printf("%s\n", describe(pick(rs, cam, px, py), rs, px, py).c_str());
                }
            }
            std::fflush(stdout);
            ctx.picks.clear();
        }
        // Streaming: the bricks this frame asked for are there for the next one (progressive).
        const rt::StreamFrame sf = stream->after_frame(s);
        if (sf.streaming && sf.progressed())
            tool::note(options.quiet, "prt-play: frame %u: %s", shown, rt::describe(sf).c_str());
        if (sf.streaming && sf.fallback_rays > 0) acc.reset();  // the image is still refining
        if (ctx.screenshot) {
            ctx.screenshot = false;
            try {  // a failed capture is said, and the window stays
                const std::filesystem::path file = next_numbered(options.save_prefix + "-%04d" + image_ext);
                write_screenshot(file, fw, fh);
                tool::note(options.quiet, "prt-play: wrote %s (%dx%d)", file.string().c_str(), fw, fh);
            } catch (const Error& e) {
                std::fprintf(stderr, "prt-play: screenshot failed: %s\n", e.what());
            }
        }
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
        char samples[64] = "";
        if (sampled)
            std::snprintf(samples, sizeof(samples), " - %s %u samples",
                          p.path_tracing ? "path tracing," : "accumulating,",
                          acc.frames() * std::max(1u, p.spp));
        char title[512];
        std::snprintf(
            title, sizeof(title),
            "prt-play - %s (%s) - %s - %.2f ms (%.1f fps), %.1f Mrays/s - shadows %s, reflections %s, "
            "refractions %s%s%s%s%s",
            backend->name().c_str(), display.path(),
            scene::surface_name(rs.models().front().view.surface).data(), smoothed_ms,
            1e3 / std::max(smoothed_ms, 1e-3), s.seconds > 0 ? s.rays() / s.seconds * 1e-6 : 0.0,
            p.shadows ? "on" : "off", p.reflections ? "on" : "off", p.refractions ? "on" : "off",
            p.deep_blending ? ", deep blending" : "", samples, recording ? " - recording" : "", streaming);
        glfwSetWindowTitle(window, title);
        if (frames > 0) {
            const double t = tool::now_seconds();
            if (shown > 1) loop_ms.push_back((t - loop_start) * 1e3);
            loop_start = t;
            render_ms.push_back(ms);
        }
        if (last) break;
    }
    if (recording && !recorded.empty()) save_recording();
    if (!loop_ms.empty()) {
        // The first frame is left out of the loop times (the window's and the kernels' first use).
        const auto median = [](std::vector<double> v) {
            std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
            return v[v.size() / 2];
        };
        const double frame = median(loop_ms);
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window, &fw, &fh);
        tool::note(options.quiet,
                   "prt-play: window %dx%d, %zu frames after the first: median %.2f ms a frame (%.1f fps), "
                   "slowest %.2f ms; render %.2f ms of it (%s, %s)",
                   fw, fh, loop_ms.size(), frame, 1e3 / std::max(frame, 1e-6),
                   *std::max_element(loop_ms.begin(), loop_ms.end()), median(render_ms),
                   backend->name().c_str(), display.path());
    }
}

}  // namespace prt::player
