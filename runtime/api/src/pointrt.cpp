// PointRT public API (prt/pointrt.h): a RenderScene and a Backend behind a pimpl; ray batches go
// to Backend::cast / Backend::occluded (prt/core/cast.h), frames to Backend::render.
#include "prt/pointrt.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <utility>

#include "prt/core/cast.h"
#include "prt/error.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"

#ifdef PRT_HAVE_CUDA
#include <cuda_runtime.h>
#endif

#ifndef PRT_API_VERSION
#define PRT_API_VERSION "0.0.0"
#endif

namespace pointrt {

namespace {

/// Runs f, turning the renderer's prt::Error (and allocation failures) into pointrt::Error.
template <class F>
auto guarded(F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const Error&) {
        throw;
    } catch (const prt::Error& e) {
        throw Error(e.what());
    } catch (const std::bad_alloc&) {
        throw Error("out of memory");
    }
}

prt::rt::Memory to_memory(Memory m) {
    return m == Memory::device ? prt::rt::Memory::device : prt::rt::Memory::host;
}

prt::core::CastRays to_cast_rays(const RayArrays& r, const prt::rt::DVec3& offset) {
    if (r.count > 0 && (r.origins == nullptr || r.directions == nullptr))
        throw Error("cast: origins and directions are required (null pointer for a non-empty batch)");
    prt::core::CastRays c;
    c.count = r.count;
    c.origins = r.origins;
    c.directions = r.directions;
    c.origins_f64 = r.origins_f64 ? 1 : 0;
    c.directions_f64 = r.directions_f64 ? 1 : 0;
    c.origin_stride = r.origin_stride != packed ? r.origin_stride : (r.origins_f64 ? 24 : 12);
    c.direction_stride = r.direction_stride != packed ? r.direction_stride : (r.directions_f64 ? 24 : 12);
    c.t_min = r.t_min;
    c.t_max = r.t_max;
    c.t_min_stride = r.t_min_stride != packed ? r.t_min_stride : 4;
    c.t_max_stride = r.t_max_stride != packed ? r.t_max_stride : 4;
    c.t_min_value = r.t_min_value;
    c.t_max_value = r.t_max_value;
    c.offset[0] = offset[0];
    c.offset[1] = offset[1];
    c.offset[2] = offset[2];
    return c;
}

CastStats to_stats(const prt::rt::CastStats& s) {
    return CastStats{s.seconds, s.device_ms, s.rays};
}

}  // namespace

std::string version() {
    return PRT_API_VERSION;
}

struct Scene::Impl {
    prt::rt::RenderScene scene;
    std::unique_ptr<prt::rt::Backend> backend;
    SceneInfo info;
    bool scene_file = false;  ///< opened from a scene file (its camera is the default view)
};

Scene::Scene(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;
Scene::~Scene() = default;

Scene Scene::open(const std::string& path, const Options& options) {
    return guarded([&] {
        namespace fs = std::filesystem;
        const fs::path p(path);
        std::error_code ec;
        if (!fs::is_regular_file(p, ec)) throw Error(path + ": no such file");
        prt::rt::LoadOptions load;
        load.surface = options.surface;
        std::string ext = p.extension().string();
        for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
        auto impl = std::make_unique<Impl>(
            Impl{ext == ".json" ? prt::rt::RenderScene::load(prt::scene::load_scene(p), {}, load)
                                : prt::rt::RenderScene::from_pool(p, load),
                 nullptr,
                 {},
                 ext == ".json"});
        if (impl->scene.has_deferred_bricks()) impl->scene.load_deferred_bricks();
        prt::rt::BackendOptions bo;
        bo.cpu_threads = options.threads;
        impl->backend = prt::rt::make_backend(options.backend, bo);
        impl->backend->set_scene(impl->scene.view());
        SceneInfo& info = impl->info;
        info.backend = impl->backend->name();
        info.device = impl->backend->device();
        for (const prt::rt::LoadedModel& m : impl->scene.models()) {
            info.surfaces.emplace_back(prt::scene::surface_name(m.view.surface));
            info.points += m.view.point_count;
        }
        const prt::rt::DVec3 lo = impl->scene.world_min(), hi = impl->scene.world_max();
        info.world_min = lo;
        info.world_max = hi;
        return Scene(std::move(impl));
    });
}

const SceneInfo& Scene::info() const {
    return m_impl->info;
}

CastStats Scene::cast(const RayArrays& rays, const HitArrays& out) {
    return guarded([&] {
        if (rays.memory != out.memory)
            throw Error("cast: the rays and the hit arrays must live in the same memory (host or device)");
        const prt::core::CastRays c = to_cast_rays(rays, m_impl->scene.render_origin());
        prt::core::CastOutputs o;
        o.hit = out.hit;
        o.valid = out.valid;
        o.t = out.t;
        o.position = out.position;
        o.normal = out.normal;
        o.color = out.color;
        o.model = out.model;
        o.element = out.element;
        return to_stats(m_impl->backend->cast(c, o, to_memory(rays.memory)));
    });
}

CastStats Scene::occluded(const RayArrays& rays, std::uint8_t* flags, std::uint8_t* valid) {
    return guarded([&] {
        if (rays.count > 0 && flags == nullptr) throw Error("occluded: flags is required (null pointer)");
        const prt::core::CastRays c = to_cast_rays(rays, m_impl->scene.render_origin());
        return to_stats(m_impl->backend->occluded(c, flags, valid, to_memory(rays.memory)));
    });
}

namespace {

/// The vector interface's rays as arrays: Ray is a struct of doubles and floats, read in place.
RayArrays arrays_of(const std::vector<Ray>& rays) {
    RayArrays a;
    a.count = rays.size();
    if (rays.empty()) return a;
    a.origins = rays.front().origin.data();
    a.directions = rays.front().direction.data();
    a.origins_f64 = a.directions_f64 = true;
    a.origin_stride = a.direction_stride = sizeof(Ray);
    a.t_min = &rays.front().t_min;
    a.t_max = &rays.front().t_max;
    a.t_min_stride = a.t_max_stride = sizeof(Ray);
    return a;
}

}  // namespace

std::vector<Hit> Scene::cast(const std::vector<Ray>& rays) {
    const std::size_t n = rays.size();
    std::vector<std::uint8_t> hit(n), valid(n);
    std::vector<float> t(n), position(n * 3), normal(n * 3), color(n * 3);
    std::vector<std::int32_t> model(n);
    std::vector<std::int64_t> element(n);
    HitArrays out{hit.data(),   valid.data(), t.data(),       position.data(), normal.data(),
                  color.data(), model.data(), element.data(), Memory::host};
    cast(arrays_of(rays), out);
    std::vector<Hit> hits(n);
    for (std::size_t i = 0; i < n; ++i) {
        Hit& h = hits[i];
        h.hit = hit[i] != 0;
        h.valid = valid[i] != 0;
        h.t = t[i];
        for (int k = 0; k < 3; ++k) {
            h.position[k] = position[i * 3 + k];
            h.normal[k] = normal[i * 3 + k];
            h.color[k] = color[i * 3 + k];
        }
        h.model = model[i];
        h.element = element[i];
    }
    return hits;
}

std::vector<std::uint8_t> Scene::occluded(const std::vector<Ray>& rays) {
    std::vector<std::uint8_t> flags(rays.size());
    occluded(arrays_of(rays), flags.data(), nullptr);
    return flags;
}

Image Scene::render(const Camera& camera, std::uint32_t width, std::uint32_t height) {
    return guarded([&] {
        if (width == 0 || height == 0 || width > 16384 || height > 16384)
            throw Error("render: width and height must be in [1, 16384], got " + std::to_string(width) +
                        " x " + std::to_string(height));
        prt::scene::Camera c;
        c.position = camera.eye;
        c.look_at = camera.look_at;
        c.up = camera.up;
        c.fov_y_degrees = camera.fov_y_degrees;
        c.width = width;
        c.height = height;
        prt::rt::FrameRequest req;
        req.camera = m_impl->scene.camera(c);
        req.params = m_impl->scene.params();
        req.width = width;
        req.height = height;
        prt::rt::Image frame;
        frame.resize(width, height);
        m_impl->backend->render(req, frame);
        Image img;
        img.width = width;
        img.height = height;
        img.rgba.resize(static_cast<std::size_t>(width) * height * 4);
        for (std::size_t i = 0; i < frame.rgba8.size(); ++i) {
            const std::uint32_t v = frame.rgba8[i];  // R in the low byte
            img.rgba[i * 4 + 0] = static_cast<std::uint8_t>(v & 0xff);
            img.rgba[i * 4 + 1] = static_cast<std::uint8_t>((v >> 8) & 0xff);
            img.rgba[i * 4 + 2] = static_cast<std::uint8_t>((v >> 16) & 0xff);
            img.rgba[i * 4 + 3] = static_cast<std::uint8_t>((v >> 24) & 0xff);
        }
        return img;
    });
}

Camera Scene::default_camera(std::uint32_t width, std::uint32_t height) const {
    return guarded([&] {
        const prt::scene::Camera c =
            m_impl->scene_file ? m_impl->scene.scene().camera : m_impl->scene.default_camera(width, height);
        Camera out;
        out.eye = c.position;
        out.look_at = c.look_at;
        out.up = c.up;
        out.fov_y_degrees = c.fov_y_degrees;
        return out;
    });
}

std::vector<std::string> available_backends() {
    std::vector<std::string> out{"cpu"};
    if (prt::rt::backend_availability().cuda_device) {
        out.emplace_back("cuda");
        out.emplace_back("hybrid");
    }
    return out;
}

void* device_malloc(std::size_t bytes) {
#ifdef PRT_HAVE_CUDA
    if (!prt::rt::backend_availability().cuda_device) throw Error("device memory: no CUDA device here");
    void* p = nullptr;
    const cudaError_t e = cudaMalloc(&p, bytes ? bytes : 1);
    if (e != cudaSuccess)
        throw Error("device memory: cudaMalloc of " + std::to_string(bytes) +
                    " bytes: " + cudaGetErrorString(e));
    return p;
#else
    (void)bytes;
    throw Error("device memory: this build has no CUDA backend");
#endif
}

void device_free(void* pointer) noexcept {
#ifdef PRT_HAVE_CUDA
    if (pointer) cudaFree(pointer);
#else
    (void)pointer;
#endif
}

void device_to_host(void* host, const void* device, std::size_t bytes) {
#ifdef PRT_HAVE_CUDA
    const cudaError_t e = cudaMemcpy(host, device, bytes, cudaMemcpyDeviceToHost);
    if (e != cudaSuccess)
        throw Error(std::string("device memory: copy to the host: ") + cudaGetErrorString(e));
#else
    (void)host, (void)device, (void)bytes;
    throw Error("device memory: this build has no CUDA backend");
#endif
}

void host_to_device(void* device, const void* host, std::size_t bytes) {
#ifdef PRT_HAVE_CUDA
    const cudaError_t e = cudaMemcpy(device, host, bytes, cudaMemcpyHostToDevice);
    if (e != cudaSuccess)
        throw Error(std::string("device memory: copy to the device: ") + cudaGetErrorString(e));
#else
    (void)host, (void)device, (void)bytes;
    throw Error("device memory: this build has no CUDA backend");
#endif
}

}  // namespace pointrt
