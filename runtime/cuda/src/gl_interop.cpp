// PointRT CUDA backend: CUDA-OpenGL interop for the player window (prt/cuda/gl_interop.h).
// Host code over the CUDA runtime API; compiled by the C++ compiler, linked into prt-play only.
#include "prt/cuda/gl_interop.h"

#include <GL/gl.h>
#include <cuda_gl_interop.h>
#include <cuda_runtime.h>

#include <string>
#include <utility>

#include "cuda_check.h"
#include "prt/error.h"

namespace prt::cuda {

struct GlPixelBuffer::Impl {
    cudaGraphicsResource_t resource = nullptr;
    bool mapped = false;
};

GlPixelBuffer::GlPixelBuffer(unsigned int gl_buffer) : m_impl(std::make_unique<Impl>()) {
    int devices = 0;
    cudaError_t e = cudaGetDeviceCount(&devices);
    if (e != cudaSuccess || devices == 0) {
        cudaGetLastError();
        throw Error(std::string("no CUDA device (") + (e != cudaSuccess ? cudaGetErrorName(e) : "none") +
                    ")");
    }
    e = cudaGraphicsGLRegisterBuffer(&m_impl->resource, static_cast<GLuint>(gl_buffer),
                                     cudaGraphicsRegisterFlagsWriteDiscard);
    if (e != cudaSuccess) {
        cudaGetLastError();  // not sticky: clear it so the backend's next call starts clean
        m_impl->resource = nullptr;
        throw Error(std::string("cudaGraphicsGLRegisterBuffer: ") + cudaGetErrorName(e) + ": " +
                    cudaGetErrorString(e) + " (is the OpenGL context on the CUDA device?)");
    }
}

GlPixelBuffer::~GlPixelBuffer() {
    if (!m_impl || !m_impl->resource) return;
    if (m_impl->mapped) cudaGraphicsUnmapResources(1, &m_impl->resource, 0);
    cudaGraphicsUnregisterResource(m_impl->resource);  // errors cannot be reported from here
}

GlPixelBuffer::GlPixelBuffer(GlPixelBuffer&&) noexcept = default;
GlPixelBuffer& GlPixelBuffer::operator=(GlPixelBuffer&&) noexcept = default;

void* GlPixelBuffer::map(std::size_t& bytes) {
    if (m_impl->mapped) throw Error("GlPixelBuffer::map: already mapped");
    // Mapping on the legacy default stream waits for earlier GL work on the buffer; the backend
    // renders on its own non-blocking stream, so wait here before handing the pointer out.
    PRT_CUDA_CHECK(cudaGraphicsMapResources(1, &m_impl->resource, 0));
    m_impl->mapped = true;
    PRT_CUDA_CHECK(cudaStreamSynchronize(0));
    void* ptr = nullptr;
    PRT_CUDA_CHECK(cudaGraphicsResourceGetMappedPointer(&ptr, &bytes, m_impl->resource));
    return ptr;
}

void GlPixelBuffer::unmap() {
    if (!m_impl->mapped) return;
    m_impl->mapped = false;
    PRT_CUDA_CHECK(cudaGraphicsUnmapResources(1, &m_impl->resource, 0));
}

}  // namespace prt::cuda
