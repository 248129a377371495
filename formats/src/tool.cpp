#include "prt/tool.h"

#include <cstdarg>
#include <cstdio>
#include <exception>
#include <new>

namespace prt::tool {

int run(int argc, char** argv, const std::string& tool, const std::string& description,
        const std::function<void(CLI::App&, CommonOptions&)>& setup,
        const std::function<void(const CommonOptions&)>& body) {
    CLI::App app{description, tool};
    app.option_defaults()->always_capture_default();
    CommonOptions common;
    app.add_flag("-q,--quiet", common.quiet, "No progress or statistics on stderr");
    app.set_version_flag("--version", std::string(PRT_VERSION));
    // Usage errors on one line, named like runtime errors: "TOOL: error: MESSAGE (see --help)".
    app.failure_message([tool](const CLI::App*, const CLI::Error& e) {
        return tool + ": error: " + e.what() + " (see --help)\n";
    });
    try {
        setup(app, common);
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? k_exit_ok : k_exit_usage_error;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: error: %s\n", tool.c_str(), e.what());
        return k_exit_usage_error;
    }
    try {
        body(common);
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "%s: error: out of memory\n", tool.c_str());
        return k_exit_runtime_error;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: error: %s\n", tool.c_str(), e.what());
        return k_exit_runtime_error;
    }
    return k_exit_ok;
}

Progress::Progress(std::string label, std::uint64_t total, bool quiet)
    : m_label(std::move(label)), m_total(total), m_quiet(quiet),
      m_start(std::chrono::steady_clock::now()), m_last(m_start) {}

Progress::~Progress() {
    if (!m_finished && m_printed) std::fputc('\n', stderr);
}

void Progress::update(std::uint64_t done) {
    if (m_quiet) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - m_last < std::chrono::milliseconds(250)) return;
    m_last = now;
    const double pct = m_total ? 100.0 * static_cast<double>(done) / static_cast<double>(m_total) : 100.0;
    std::fprintf(stderr, "\r%s: %5.1f%%", m_label.c_str(), pct);
    m_printed = true;
    std::fflush(stderr);
}

void Progress::finish() {
    if (m_finished) return;
    m_finished = true;
    if (m_quiet) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    std::fprintf(stderr, "\r%s: done in %.3f s\n", m_label.c_str(), s);
}

void note(bool quiet, const char* format, ...) {
    if (quiet) return;
    va_list args;
    va_start(args, format);
    std::vfprintf(stderr, format, args);
    va_end(args);
    std::fputc('\n', stderr);
}

double now_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace prt::tool
