// PointRT CUDA backend: CUDA-OpenGL interop for the player window. The CUDA backend writes each
// frame's display-encoded pixels straight into an OpenGL pixel-buffer object (PBO), which the
// window then copies into its texture on the GPU (glTexSubImage2D from the bound PBO): the frame
// never travels to the host and back. thesis 2.4 (Fig. 2.6) names "copying the CUDA output buffer
// to a Pixel Buffer Object for display" as the player's CPU overhead; this removes that copy.
//
// Plain C++ header (no CUDA or OpenGL types), so the window (compiled by g++) can include it.
// Implemented in runtime/cuda/src/gl_interop.cpp; built (target prt_cuda_gl) only with CUDA and
// OpenGL. Registration fails where the GL context does not run on the CUDA device (Mesa, Xvfb,
// another vendor's GPU): the caller then keeps the texture upload.
#pragma once

#include <cstddef>
#include <memory>

namespace prt::cuda {

/// A GL buffer object registered with CUDA (cudaGraphicsGLRegisterBuffer, write-discard), mapped
/// for one frame at a time. Move-only; unregisters on destruction (needs the GL context current).
class GlPixelBuffer {
public:
    /// Registers GL buffer object `gl_buffer` (its name from glGenBuffers, storage already
    /// allocated with glBufferData) with CUDA device 0. Throws prt::Error with one line when CUDA
    /// refuses (no CUDA device, the context is not on an NVIDIA GPU, ...).
    explicit GlPixelBuffer(unsigned int gl_buffer);
    ~GlPixelBuffer();
    GlPixelBuffer(GlPixelBuffer&&) noexcept;
    GlPixelBuffer& operator=(GlPixelBuffer&&) noexcept;
    GlPixelBuffer(const GlPixelBuffer&) = delete;
    GlPixelBuffer& operator=(const GlPixelBuffer&) = delete;

    /// Maps the buffer for CUDA and returns its device pointer; `bytes` gets its size. GL work
    /// issued before the call is complete when it returns. Throws prt::Error.
    void* map(std::size_t& bytes);
    /// Hands the buffer back to OpenGL; CUDA work on it must be complete (the backends synchronize
    /// before render() returns). Throws prt::Error.
    void unmap();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace prt::cuda
