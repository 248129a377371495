// PointRT player: progressive accumulation of sampled frames (seed 002, 7: path tracing converges
// over many samples). Each frame draws new samples (RenderParams::frame); the image shown or
// written is the running mean of every frame since the last reset (the camera moved).
#pragma once

#include <cstdint>
#include <vector>

#include "prt/core/shading.h"
#include "prt/runtime/image.h"

namespace prt::player {

class Accumulator {
public:
    void reset() {
        m_sum.clear();
        m_frames = 0;
    }
    /// Frames in the mean so far (the next frame's RenderParams::frame).
    std::uint32_t frames() const { return m_frames; }
    /// Adds the frame's linear radiance and replaces `image` (rgb and its display encoding with
    /// `params`) by the mean of all frames added since reset().
    void add(rt::Image& image, const core::RenderParams& params) {
        if (m_sum.size() != image.rgb.size()) {
            m_sum.assign(image.rgb.size(), 0.0);
            m_frames = 0;
        }
        ++m_frames;
        const double inv = 1.0 / m_frames;
        for (std::size_t i = 0; i < m_sum.size(); ++i) {
            m_sum[i] += image.rgb[i];
            image.rgb[i] = static_cast<float>(m_sum[i] * inv);
        }
        for (std::size_t i = 0; i < image.rgba8.size(); ++i) {
            const core::Vec3 v{image.rgb[3 * i], image.rgb[3 * i + 1], image.rgb[3 * i + 2]};
            image.rgba8[i] = core::pack_rgba8(core::encode_display(v, params));
        }
    }

private:
    std::vector<double> m_sum;
    std::uint32_t m_frames = 0;
};

}  // namespace prt::player
