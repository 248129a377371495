#include "prt/runtime/backend.h"

#include "prt/core/render.h"
#include "prt/error.h"
#include "prt/runtime/brick_stream.h"

namespace prt::rt {

FrameStats& FrameStats::operator+=(const FrameStats& o) {
    seconds += o.seconds;
    device_ms += o.device_ms;
    pixels += o.pixels;
    heavy_first += o.heavy_first;
    core::add_ray_counters(*this, o);
    return *this;
}

FrameStats& FrameStats::operator+=(const core::RayCounters& c) {
    core::add_ray_counters(*this, c);
    return *this;
}

CastStats Backend::cast(const core::CastRays&, const core::CastOutputs&, Memory) {
    throw Error("backend " + name() + " cannot cast rays");
}

CastStats Backend::occluded(const core::CastRays&, std::uint8_t*, std::uint8_t*, Memory) {
    throw Error("backend " + name() + " cannot cast rays");
}

std::unique_ptr<BrickStorage> Backend::make_brick_storage(std::uint32_t, const core::BrickView&,
                                                          const BrickArena&) {
    return nullptr;
}

}  // namespace prt::rt
