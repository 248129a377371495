// PointRT CUDA: a scene's arrays on the GPU. upload() copies every array a SceneView points to
// (each pool array once, however many models share it) and keeps a SceneView whose pointers are
// the device copies, for kernels: the renderer's (cuda_backend.cu) and prt-photons'.
// Include from CUDA translation units only (it names cudaStream_t).
#pragma once

#include <cuda_runtime.h>

#include <memory>

#include "prt/core/scene_view.h"
#include "prt/runtime/backend.h"

namespace prt::cuda {

class DeviceScene {
public:
    DeviceScene();
    ~DeviceScene();
    DeviceScene(const DeviceScene&) = delete;
    DeviceScene& operator=(const DeviceScene&) = delete;

    /// Replaces the device copy by `host`'s arrays. Before allocating, checks that the bytes fit
    /// in the device's free memory: if not, throws prt::Error with the bytes needed and free and
    /// what to do (a coarser ISO, a culled or smaller pool). Other CUDA failures throw one line.
    rt::UploadStats upload(const core::SceneView& host, cudaStream_t stream);
    /// The scene with device pointers (valid until the next upload or destruction).
    const core::SceneView& view() const;
    /// Model i as on the device (device pointers).
    const core::ModelView& model(std::uint32_t i) const;
    /// Replaces model i's brick view on the device (streamed bricks: the brick storage's arena,
    /// resident table, leaf bounds and flags; device pointers). Synchronous.
    void set_model_bricks(std::uint32_t i, const core::BrickView& bricks);
    /// Bytes the arrays of `host` take on the device.
    static std::uint64_t device_bytes(const core::SceneView& host);

private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace prt::cuda
