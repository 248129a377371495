// The tool harness's parts without a command-line parser (prt/tool_util.h).
#include "prt/tool_util.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>

namespace prt::tool {

Progress::Progress(std::string label, std::uint64_t total, bool quiet)
    : m_label(std::move(label)),
      m_total(total),
      m_quiet(quiet),
      m_terminal(::isatty(::fileno(stderr)) != 0),
      m_start(std::chrono::steady_clock::now()),
      m_last(m_start) {}

Progress::~Progress() {
    if (!m_finished && m_printed && m_terminal) std::fputc('\n', stderr);
}

bool Progress::log_line_due(double since_last_s, double pct, double last_pct) {
    // A log gets few, whole lines: at most one a second, and then only once the step moved on by
    // 10 % or 10 s passed without a line (a slow step still shows it is alive).
    return since_last_s >= 1.0 && (pct - last_pct >= 10.0 || since_last_s >= 10.0);
}

void Progress::update(std::uint64_t done) {
    if (m_quiet) return;
    const auto now = std::chrono::steady_clock::now();
    const double pct = m_total ? 100.0 * static_cast<double>(done) / static_cast<double>(m_total) : 100.0;
    if (m_terminal) {
        if (now - m_last < std::chrono::milliseconds(250)) return;
    } else if (!log_line_due(std::chrono::duration<double>(now - m_last).count(), pct, m_last_pct)) {
        return;
    }
    m_last = now;
    m_last_pct = pct;
    const double elapsed = std::chrono::duration<double>(now - m_start).count();
    // A terminal: one line rewritten in place ('\r'); a file or pipe: one whole line per update.
    const char* start = m_terminal ? "\r" : "";
    const char* end = m_terminal ? "   " : "\n";
    if (elapsed >= 1.0 && pct >= 1.0 && pct < 100.0) {
        const double left = elapsed * (100.0 - pct) / pct;
        std::fprintf(stderr, "%s%s: %5.1f%%, about %.0f s left%s", start, m_label.c_str(), pct,
                     std::ceil(left), end);
    } else {
        std::fprintf(stderr, "%s%s: %5.1f%%%s", start, m_label.c_str(), pct, m_terminal ? "" : "\n");
    }
    m_printed = true;
    std::fflush(stderr);
}

void Progress::finish() {
    if (m_finished) return;
    m_finished = true;
    if (m_quiet) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    std::fprintf(stderr, "%s%s: done in %.3f s\n", m_terminal ? "\r" : "", m_label.c_str(), s);
}

void note(bool quiet, const char* format, ...) {
    if (quiet) return;
    va_list args;
    va_start(args, format);
    vnote(format, args);
    va_end(args);
}

void vnote(const char* format, va_list args) {
    std::vfprintf(stderr, format, args);
    std::fputc('\n', stderr);
}

std::uint64_t parse_byte_size(const std::string& text, const char* what) {
    const auto bad = [&]() {
        return Error(std::string(what) + ": '" + text + "' is not a size (e.g. 512M, 4G)");
    };
    std::size_t used = 0;
    double value = 0;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {
        throw bad();
    }
    if (text.empty() || (!std::isdigit(static_cast<unsigned char>(text[0])) && text[0] != '.')) throw bad();
    std::string suffix = text.substr(used);
    for (char& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    double scale = 1;
    if (!suffix.empty() && std::string("KMGT").find(suffix[0]) != std::string::npos) {
        scale = std::pow(1024.0, double(std::string("KMGT").find(suffix[0]) + 1));
        suffix.erase(0, 1);
        if (suffix == "IB" || suffix == "B") suffix.clear();
    } else if (suffix == "B") {
        suffix.clear();
    }
    const double bytes = value * scale;
    if (!suffix.empty() || !std::isfinite(bytes) || bytes < 1 || bytes > 1.8e19) throw bad();
    return static_cast<std::uint64_t>(bytes);
}

std::uint64_t physical_memory_bytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
    return pages > 0 && page > 0 ? std::uint64_t(pages) * std::uint64_t(page) : 0;
}

std::uint64_t memory_limit(const std::string& text) {
    return text.empty() ? std::max<std::uint64_t>(physical_memory_bytes() / 2, std::uint64_t(256) << 20)
                        : parse_byte_size(text, "--memory");
}

std::string format_bytes(std::uint64_t bytes) {
    char buf[64];
    const char* units[] = {"KiB", "MiB", "GiB", "TiB"};
    double v = double(bytes);
    if (bytes < 1024) {
        std::snprintf(buf, sizeof buf, "%llu B", static_cast<unsigned long long>(bytes));
        return buf;
    }
    int u = -1;
    while (v >= 1024 && u < 3) v /= 1024, ++u;
    std::snprintf(buf, sizeof buf, "%.*f %s", v < 10 ? 2 : 1, v, units[u]);
    return buf;
}

void check_input_file(const std::filesystem::path& path) {
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(st)) throw Error(path.string() + ": no such file");
    if (std::filesystem::is_directory(st)) throw Error(path.string() + ": is a folder, not a file");
    if (::access(path.c_str(), R_OK) != 0)
        throw Error(path.string() + ": cannot read: " + std::strerror(errno));
}

double now_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace prt::tool
