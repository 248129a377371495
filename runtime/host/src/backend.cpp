#include "prt/runtime/backend.h"

#include "prt/core/render.h"

namespace prt::rt {

FrameStats& FrameStats::operator+=(const FrameStats& o) {
    seconds += o.seconds;
    device_ms += o.device_ms;
    pixels += o.pixels;
    core::add_ray_counters(*this, o);
    return *this;
}

FrameStats& FrameStats::operator+=(const core::RayCounters& c) {
    core::add_ray_counters(*this, c);
    return *this;
}

}  // namespace prt::rt
