// PointRT prt-import: progress that appears only for steps that take a while. Small inputs print
// nothing, so an input that fails early gives exactly one error line on stderr.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "prt/tool_util.h"

namespace prt::pre::import {

class LazyProgress {
public:
    LazyProgress(std::string label, std::uint64_t total, bool quiet)
        : m_label(std::move(label)), m_total(total), m_quiet(quiet), m_start(tool::now_seconds()) {}

    /// Call every few thousand items; starts reporting once the step has run for 0.3 s.
    void update(std::uint64_t done) {
        if (m_quiet) return;
        if (!m_progress) {
            if (tool::now_seconds() - m_start < 0.3) return;
            m_progress.emplace(m_label, m_total, false);
        }
        m_progress->update(done);
    }
    void finish() {
        if (m_progress) m_progress->finish();
    }

private:
    std::string m_label;
    std::uint64_t m_total;
    bool m_quiet;
    double m_start;
    std::optional<tool::Progress> m_progress;
};

}  // namespace prt::pre::import
