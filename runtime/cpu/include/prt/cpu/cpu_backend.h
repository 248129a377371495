// PointRT CPU backend: runs the core's per-pixel function (prt/core/render.h) over all cores through
// prt::parallel_chunks (prt/parallel.h), 16x16 tiles taken from an atomic counter. It is the reference
// the CUDA backend is compared against, and the path CI tests.
#pragma once

#include <memory>

#include "prt/runtime/backend.h"

namespace prt::cpu {

/// Creates the CPU backend with `threads` workers (0: every core the process may use).
std::unique_ptr<rt::Backend> make_cpu_backend(unsigned threads = 0);

}  // namespace prt::cpu
