// PointRT preprocess: which backend a step with a GPU path runs on (--backend auto|cpu|cuda: radii,
// octree, culling). One rule and one set of messages for every tool.
#pragma once

#include <string>

#include "prt/error.h"

namespace prt::pre {

/// For a build without a CUDA path: no device is ever usable, and says why.
inline bool no_cuda_build(std::string* reason) {
    if (reason)
        *reason = "this build has no CUDA backend (configured without nvcc or with PRT_WITH_CUDA=OFF)";
    return false;
}

/// The backend for --backend `name`: "cpu" for cpu; for cuda or auto, "cuda" when `usable(&reason)`
/// says a device can be used (called only then). Otherwise cuda throws prt::Error
/// "--backend cuda: REASON (use --backend cpu)" and auto falls back to "cpu", `why` (if given)
/// getting the reason. Any other name throws.
template <class Usable>
std::string choose_backend(const std::string& name, Usable&& usable, std::string* why = nullptr) {
    if (name == "cpu") return "cpu";
    if (name != "cuda" && name != "auto")
        throw Error("unknown backend '" + name + "' (expected auto, cpu or cuda)");
    std::string reason;
    if (usable(&reason)) return "cuda";
    if (name == "cuda") throw Error("--backend cuda: " + reason + " (use --backend cpu)");
    if (why) *why = reason;
    return "cpu";
}

}  // namespace prt::pre
