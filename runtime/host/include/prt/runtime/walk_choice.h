#pragma once
// Which of two kernels a kind of frame runs, chosen by timing them (the CUDA backend's ISO walk
// with macro-regions or without: rt::BackendOptions::cuda_iso_walk "auto"). Host logic only, so it
// is tested without a GPU.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace prt::rt {

/// Per kind of frame (a key: the kernel mask and the image size), frame 0 runs kernel 0 untimed (cold
/// caches, first launch), frames 1-4 run kernel 0, 1, 0, 1 and keep each one's best time, then the
/// faster runs and every k_recheck-th frame the other once; the choice then follows the two latest
/// times, switching when the other is k_margin faster (so noise does not flip it). A view that moves
/// to where the other kernel pays switches within k_recheck frames; a steady view spends 1 frame in
/// k_recheck on the slower one.
class WalkChoice {
public:
    using Key = std::array<std::uint32_t, 3>;
    static constexpr std::uint32_t k_trial_frames = 5;  ///< frame 0 (untimed) and 4 timed trials
    static constexpr std::uint32_t k_recheck = 64;
    static constexpr float k_margin = 0.98f;
    static constexpr std::size_t k_max_kinds = 32;  ///< kinds remembered; the oldest goes first

    /// The kernel (0 or 1) the next frame of kind `key` runs; record() its time next.
    int next(const Key& key) {
        m_current = &entry(key);
        Entry& e = *m_current;
        if (e.frames < k_trial_frames) {
            m_running = e.frames == 0 ? 0 : static_cast<int>((e.frames + 1) % 2);  // 0, 0, 1, 0, 1
        } else {
            m_running = e.frames % k_recheck == 0 ? 1 - e.chosen : e.chosen;
        }
        return m_running;
    }

    /// The time of the frame next() chose the kernel for, in one unit for every frame of its kind
    /// (the CUDA backend: nanoseconds per pixel).
    void record(float time) {
        if (m_current == nullptr) return;
        Entry& e = *m_current;
        m_current = nullptr;
        const std::uint32_t frame = e.frames++;
        if (frame == 0 || !(time > 0.0f)) return;  // the cold frame; a frame with no time
        float& t = e.time[m_running];
        if (frame < k_trial_frames) {
            t = t > 0.0f ? (time < t ? time : t) : time;
            if (frame + 1 == k_trial_frames) e.chosen = e.time[1] < e.time[0] ? 1 : 0;
            return;
        }
        t = time;
        const int other = 1 - e.chosen;
        if (e.time[other] > 0.0f && e.time[other] < k_margin * e.time[e.chosen]) e.chosen = other;
    }

    /// The kernel kind `key` runs outside its checks (0 before its trials end).
    int chosen(const Key& key) const {
        for (const Entry& e : m_entries)
            if (e.key == key) return e.chosen;
        return 0;
    }

private:
    struct Entry {
        Key key{};
        std::uint32_t frames = 0;
        std::array<float, 2> time{0.0f, 0.0f};  ///< best trial time, then latest time, per kernel
        int chosen = 0;
    };

    Entry& entry(const Key& key) {
        for (Entry& e : m_entries)
            if (e.key == key) return e;
        if (m_entries.size() >= k_max_kinds) m_entries.erase(m_entries.begin());  // a window resized often
        m_entries.push_back(Entry{key});
        return m_entries.back();
    }

    std::vector<Entry> m_entries;
    Entry* m_current = nullptr;  ///< the entry of the frame next() answered (its vector grows only in next())
    int m_running = 0;
};

}  // namespace prt::rt
