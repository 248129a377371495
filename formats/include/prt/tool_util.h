// PointRT: the parts of the tool harness that need no command-line parser: progress and notes on
// stderr, byte sizes (--memory), input-file checks, a clock. Libraries include this header; only a
// tool's main translation unit includes prt/tool.h, which adds CLI11 (a heavy header: about 20 s
// of compile time a translation unit under the sanitizers, so it stays out of the libraries).
#pragma once

#include <chrono>
#include <cstdarg>
#include <cstdint>
#include <filesystem>
#include <string>

#include "prt/error.h"

namespace prt::tool {

/// Progress of a long step on stderr, silent when quiet. On a terminal, one line rewritten in place
/// ('\r') at most a few times a second; when stderr is a file or a pipe (isatty), whole lines
/// ending in '\n' instead, at most one a second and only after 10 % more or 10 s without one
/// (log_line_due), so that logs stay readable. Once a step has run a second and is past 1 %, the
/// line also shows an estimate of the time left (elapsed x remaining / done: a straight
/// extrapolation of the rate so far).
class Progress {
public:
    Progress(std::string label, std::uint64_t total, bool quiet);
    ~Progress();
    /// Reports `done` of `total` (thread-safe enough for one reporting thread).
    void update(std::uint64_t done);
    /// Prints the final line with the elapsed time.
    void finish();
    /// Whether a log (stderr not a terminal) gets a line now: `since_last_s` seconds and
    /// `pct - last_pct` percent after the previous line (or the start).
    static bool log_line_due(double since_last_s, double pct, double last_pct);

private:
    std::string m_label;
    std::uint64_t m_total;
    bool m_quiet;
    bool m_finished = false;
    bool m_terminal;         ///< stderr is a terminal: '\r' updates of one line
    bool m_printed = false;  ///< a partial line is on stderr (terminal)
    double m_last_pct = 0;   ///< percent shown on the last line
    std::chrono::steady_clock::time_point m_start;
    std::chrono::steady_clock::time_point m_last;
};

/// A byte count as users write it: a number with an optional suffix K, M, G or T (powers of 1024,
/// case-insensitive, an optional trailing "B" or "iB": "512M", "1.5G", "4GiB", "1000"). Throws
/// prt::Error "WHAT: 'TEXT' is not a size (e.g. 512M, 4G)" on anything else or on 0.
std::uint64_t parse_byte_size(const std::string& text, const char* what = "size");

/// The machine's physical memory in bytes (sysconf), or 0 when unknown.
std::uint64_t physical_memory_bytes();

/// The --memory of the out-of-core tools: parse_byte_size(text, "--memory"), or when `text` is
/// empty half the physical memory (at least 256 MiB).
std::uint64_t memory_limit(const std::string& text);

/// "1.50 GiB", "512.0 MiB", "12.0 KiB", "100 B" (messages).
std::string format_bytes(std::uint64_t bytes);

/// Statistics and notes for the user on stderr unless quiet (printf-style).
void note(bool quiet, const char* format, ...) __attribute__((format(printf, 2, 3)));
/// note()'s line from a va_list (PoolStep::note).
void vnote(const char* format, va_list args);

/// An input file the tool is about to read: throws prt::Error "PATH: no such file" (or "is a
/// folder, not a file", "cannot read: reason"), which tool::run prints on one line with exit 1
/// (CLI11's ExistingFile check would make it a usage error, exit 2, in CLI11's wording).
void check_input_file(const std::filesystem::path& path);

/// Seconds since an arbitrary start, monotonic.
double now_seconds();

}  // namespace prt::tool
