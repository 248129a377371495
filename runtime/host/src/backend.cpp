#include "prt/runtime/backend.h"

namespace prt::rt {

FrameStats& FrameStats::operator+=(const FrameStats& o) {
    seconds += o.seconds;
    device_ms += o.device_ms;
    pixels += o.pixels;
    primary += o.primary;
    secondary += o.secondary;
    shadow += o.shadow;
    leaves += o.leaves;
    splat_tests += o.splat_tests;
    truncated += o.truncated;
    sanitized += o.sanitized;
    dropped += o.dropped;
    culled += o.culled;
    return *this;
}

}  // namespace prt::rt
