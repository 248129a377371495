// PointRT: the public C++ API (issue 18). Open a pool or a scene file, cast batches of rays against
// it (closest hits or occlusion) on the CPU or the GPU, render images. This one header is all a
// user includes; the renderer's own headers stay inside the library (pimpl).
//
//     find_package(PointRT REQUIRED)
//     target_link_libraries(app PRIVATE PointRT::pointrt)
//
//     pointrt::Scene scene = pointrt::Scene::open("room.pool");  // backend "auto"
//     std::vector<pointrt::Ray> rays = {{{0, 0, 5}, {0, 0, -1}}};
//     std::vector<pointrt::Hit> hits = scene.cast(rays);
//
// Frames: every position is in the world frame of the scene (pools' ModelInfo::origin, the scene
// file's transforms); the library moves rays into its render frame in double, so scans far from the
// world origin keep their precision. A ray is origin + t * direction, t in [t_min, t_max), t in
// units of the direction's length (the direction need not be unit), as in Embree and Open3D.
// Errors throw pointrt::Error (a std::runtime_error) with one line naming the file and the problem.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace pointrt {

/// The library's version, "major.minor.patch".
std::string version();

/// Every error of the library: one line naming the file or argument and what is wrong.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// How a scene is opened.
struct Options {
    /// "cpu", "cuda", "hybrid" (ray batches on the GPU) or "auto" (cuda when a GPU is there, else cpu).
    std::string backend = "auto";
    /// Surface traced for every model: "" keeps the scene file's (a pool alone: what it holds),
    /// "auto", "splats", "iso", "mls" or "patches" (the pool must hold those sections).
    std::string surface;
    /// CPU backend threads; 0: every core the process may use.
    unsigned threads = 0;
};

/// Where the arrays of a RayArrays / HitArrays live.
enum class Memory {
    host,   ///< ordinary memory (both backends; the CUDA backend copies it to the GPU and back)
    device  ///< memory of the GPU the CUDA backend runs on (no copies); the CPU backend throws
};

/// One ray (the convenience interface: Scene::cast(std::vector<Ray>)).
struct Ray {
    std::array<double, 3> origin{0, 0, 0};
    std::array<double, 3> direction{0, 0, 1};
    float t_min = 0.0f;
    float t_max = std::numeric_limits<float>::infinity();
};

/// One answer of Scene::cast(std::vector<Ray>).
struct Hit {
    bool hit = false;    ///< false for misses and invalid rays
    bool valid = false;  ///< false for NaN/infinite input, a zero-length direction or t_min < 0
    float t = std::numeric_limits<float>::infinity();
    std::array<float, 3> position{};  ///< world frame
    std::array<float, 3> normal{};    ///< unit, outward as stored (not turned toward the ray)
    std::array<float, 3> color{};     ///< the surface's point colour in [0, 1] (sRGB); 1 without colours
    std::int32_t model = -1;          ///< index of the scene's model hit
    std::int64_t element = -1;        ///< source point (splats, MLS), patch index (patches), else -1
};

/// RayArrays' strides: the default, values of consecutive rays back to back.
inline constexpr std::size_t packed = ~std::size_t{0};

/// A batch of rays as arrays (the fast interface): structure of arrays, strides in bytes between
/// rays (`packed`: back to back; 0: the same value for every ray, e.g. one origin for all).
struct RayArrays {
    std::size_t count = 0;
    const void* origins = nullptr;     ///< 3 values per ray: float, or double when origins_f64
    const void* directions = nullptr;  ///< 3 values per ray: float, or double when directions_f64
    bool origins_f64 = false, directions_f64 = false;
    std::size_t origin_stride = packed, direction_stride = packed;
    const float* t_min = nullptr;  ///< per ray (stride t_min_stride), or null: t_min_value for all
    const float* t_max = nullptr;  ///< per ray, or null: t_max_value for all
    std::size_t t_min_stride = packed, t_max_stride = packed;
    float t_min_value = 0.0f;
    float t_max_value = std::numeric_limits<float>::infinity();
    Memory memory = Memory::host;
};

/// Where Scene::cast(RayArrays, HitArrays) writes (each optional: null is not written; packed).
struct HitArrays {
    std::uint8_t* hit = nullptr;      ///< count: 1 hit, 0 miss or invalid
    std::uint8_t* valid = nullptr;    ///< count: 0 for invalid rays
    float* t = nullptr;               ///< count: +inf for misses
    float* position = nullptr;        ///< count x 3, world frame
    float* normal = nullptr;          ///< count x 3
    float* color = nullptr;           ///< count x 3
    std::int32_t* model = nullptr;    ///< count: -1 for misses
    std::int64_t* element = nullptr;  ///< count: -1 where none
    Memory memory = Memory::host;     ///< must match the rays' memory
};

/// Timing of one batch.
struct CastStats {
    double seconds = 0;    ///< wall time of the call, copies included
    double device_ms = 0;  ///< GPU kernel time (0 on the CPU)
    std::uint64_t rays = 0;
};

/// A pinhole camera in the world frame.
struct Camera {
    std::array<double, 3> eye{0, 0, 5};
    std::array<double, 3> look_at{0, 0, 0};
    std::array<double, 3> up{0, 1, 0};
    double fov_y_degrees = 45.0;  ///< vertical field of view
};

/// An 8-bit RGBA image, row 0 at the top, display-encoded (the renderer's tone mapping and gamma).
struct Image {
    std::uint32_t width = 0, height = 0;
    std::vector<std::uint8_t> rgba;  ///< width * height * 4
};

/// Surfaces, bounds and backend of an open scene.
struct SceneInfo {
    std::string backend;                ///< "cpu", "cuda" or "hybrid"
    std::string device;                 ///< one line: CPU threads or GPU name
    std::vector<std::string> surfaces;  ///< per model: splats, iso, mls or patches
    std::array<double, 3> world_min{}, world_max{};
    std::uint64_t points = 0;  ///< points over all models
};

/// An open scene: its pools mapped, uploaded to the backend. Move-only. One call at a time per
/// Scene (the CUDA backend's stream and buffers are the scene's); open one Scene per thread otherwise.
class Scene {
public:
    /// Opens a pool (*.pool, as built by the prt-* tools) or a scene file (*.json, formats/SCENE.md).
    /// Throws Error naming the file when it cannot be read or lacks the sections to trace.
    static Scene open(const std::string& path, const Options& options = {});

    Scene(Scene&&) noexcept;
    Scene& operator=(Scene&&) noexcept;
    ~Scene();

    const SceneInfo& info() const;

    /// Closest hits of a batch of rays, written into `out` (the fast path: no copies on the
    /// backend that owns the memory). Invalid rays are reported per ray, never thrown.
    CastStats cast(const RayArrays& rays, const HitArrays& out);
    /// Occlusion of a batch: flags[i] = 1 when anything lies on [t_min, t_max) of ray i; `valid`
    /// (optional) 0 for invalid rays (whose flag is 0).
    CastStats occluded(const RayArrays& rays, std::uint8_t* flags, std::uint8_t* valid = nullptr);

    /// Convenience: closest hits of a vector of rays.
    std::vector<Hit> cast(const std::vector<Ray>& rays);
    /// Convenience: whether each ray is blocked on [t_min, t_max) (invalid rays: false).
    std::vector<std::uint8_t> occluded(const std::vector<Ray>& rays);

    /// Renders an image with the scene's materials and lights (a pool alone: the default light);
    /// spp > 1 or path tracing as the scene file says.
    Image render(const Camera& camera, std::uint32_t width, std::uint32_t height);
    /// The default view of the scene (the scene file's camera, or a framing of a pool's points).
    Camera default_camera(std::uint32_t width = 512, std::uint32_t height = 512) const;

private:
    struct Impl;
    explicit Scene(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

/// Which backends this build and machine can run: "cpu" always, "cuda" and "hybrid" with a GPU.
std::vector<std::string> available_backends();

/// Device memory on the CUDA backend's GPU (outputs for Memory::device batches when the caller has
/// none). Throws Error in builds or on machines without CUDA.
void* device_malloc(std::size_t bytes);
/// Frees device_malloc()'s memory (null: nothing).
void device_free(void* pointer) noexcept;
/// Copies `bytes` from device memory to host memory.
void device_to_host(void* host, const void* device, std::size_t bytes);
/// Copies `bytes` from host memory to device memory.
void host_to_device(void* device, const void* host, std::size_t bytes);

}  // namespace pointrt
