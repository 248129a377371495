#include "prt/tool.h"

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
#include <fstream>
#include <new>
#include <vector>

#include "prt/atomic_file.h"
#include "prt/formats/gi_sections.h"
#include "prt/pool_step.h"
#include "prt/scene_pools.h"

namespace prt::tool {

namespace {

/// The paths ExistingInput saw during the current parse, checked by run() before the body.
std::vector<std::string>& pending_inputs() {
    static std::vector<std::string> paths;
    return paths;
}

}  // namespace

const CLI::Validator ExistingInput(
    [](std::string& path) {
        pending_inputs().push_back(path);
        return std::string();
    },
    "FILE", "EXISTING_INPUT");

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
    pending_inputs().clear();
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
        for (const std::string& path : pending_inputs()) check_input_file(path);
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

namespace {

void vnote(const char* format, va_list args) {
    std::vfprintf(stderr, format, args);
    std::fputc('\n', stderr);
}

}  // namespace

void note(bool quiet, const char* format, ...) {
    if (quiet) return;
    va_list args;
    va_start(args, format);
    vnote(format, args);
    va_end(args);
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

void write_json_file(const std::string& path, const nlohmann::json& stats) {
    std::ofstream out(path);
    out << stats.dump(2) << "\n";
    if (!out) throw Error(path + ": cannot write the statistics");
}

void StagedProgress::update(const char* stage, std::uint64_t done, std::uint64_t total) {
    if (!m_bar || m_stage != stage) {
        if (m_bar) m_bar->finish();
        m_stage = stage;
        m_bar = std::make_unique<Progress>(m_tool + ": " + stage, total, m_quiet);
    }
    m_bar->update(done);
}

void StagedProgress::finish() {
    if (m_bar) m_bar->finish();
}

PoolStep::PoolStep(std::string tool, std::string description, Help help)
    : m_tool(std::move(tool)), m_description(std::move(description)), m_help(std::move(help)) {}

int PoolStep::run(int argc, char** argv, const std::function<void(CLI::App&)>& options,
                  const std::function<void(PoolStep&)>& body) {
    return tool::run(
        argc, argv, m_tool, m_description,
        [&](CLI::App& app, CommonOptions&) {
            if (!m_help.input.empty()) app.add_option(m_help.input_name, m_input, m_help.input)->required();
            CLI::Option* output = nullptr;
            if (!m_help.output.empty()) output = app.add_option("-o,--output", m_output, m_help.output);
            options(app);
            if (output && m_output_unused) {
                // Required unless this run writes no OUTPUT: known only once every option parsed.
                app.parse_complete_callback([this, output] {
                    const std::string why = m_output_unused();
                    if (why.empty() && m_output.empty()) throw CLI::RequiredError(output->get_name());
                    if (!why.empty() && !m_output.empty()) {
                        m_ignored_output = "-o " + m_output + " ignored: " + why;
                        m_output.clear();
                    }
                });
            } else if (output) {
                output->required();
            }
            if (!m_help.stats.empty()) app.add_option("--stats-json", m_stats, m_help.stats);
            if (!m_help.output.empty() || !m_help.input.empty())
                app.add_option("--provenance-tag", m_tag,
                               "JSON value recorded as \"tag\" in this step's provenance parameters "
                               "(scripts/prt-batch records the input's hash and its arguments there) "
                               "[none]")
                    ->check([](const std::string& value) {
                        return nlohmann::json::accept(value)
                                   ? std::string()
                                   : std::string("--provenance-tag is not valid JSON");
                    });
        },
        [&](const CommonOptions& common) {
            m_common = common;
            m_start = now_seconds();
            if (!m_ignored_output.empty()) note("%s: %s", m_tool.c_str(), m_ignored_output.c_str());
            if (m_output_in_place && m_output.empty()) m_output = m_input;
            // Refused before any work: a missing input, then an output that cannot be written.
            const bool input_unused = m_input_unused && !m_input_unused().empty();
            if (!m_input.empty() && !input_unused) check_input_file(m_input);
            if (!m_output.empty()) check_writable(m_output);
            if (!m_stats.empty()) check_writable(m_stats);
            body(*this);
        });
}

CLI::Option* PoolStep::add_memory(CLI::App& app, std::string& text, const std::string& help) {
    return app.add_option("--memory", text, help)
        ->check(
            [](const std::string& value) {
                try {
                    tool::parse_byte_size(value, "--memory");
                    return std::string();
                } catch (const Error& e) {
                    return std::string(e.what());
                }
            },
            "SIZE");
}

CLI::Option* PoolStep::add_output(CLI::App& app, const std::string& help) {
    m_output_in_place = true;
    return app.add_option("-o,--output", m_output, help);
}

void PoolStep::output_unused_when(std::function<std::string()> unused) {
    m_output_unused = std::move(unused);
}

void PoolStep::input_unused_when(std::function<std::string()> unused) {
    m_input_unused = std::move(unused);
}

const pool::PoolFile& PoolStep::input() {
    if (!m_in) m_in.emplace(pool::PoolFile::open(m_input));
    return *m_in;
}

pool::PoolWriter& PoolStep::writer() {
    if (!m_writer) {
        m_writer.emplace();
        if (!m_help.input.empty()) m_writer->carry_over(input());
    }
    return *m_writer;
}

bool PoolStep::drop_sections(std::initializer_list<pool::SectionType> types) {
    pool::PoolWriter& w = writer();
    bool dropped = false;
    for (const pool::SectionType t : types) {
        dropped |= w.has(t);
        w.remove(t);
    }
    return dropped;
}

void PoolStep::check_output_folder() const {
    check_writable(m_output);
}

std::uint64_t PoolStep::write(const nlohmann::json& parameters) {
    return write(parameters.dump());
}

std::uint64_t PoolStep::write(const std::string& parameters_json) {
    pool::PoolWriter& w = writer();
    if (m_tag.empty()) {
        w.add_provenance(m_tool, PRT_VERSION, parameters_json);
    } else {
        nlohmann::json parameters = nlohmann::json::parse(parameters_json, nullptr, false);
        if (!parameters.is_object()) parameters = {{"parameters", parameters_json}};
        parameters["tag"] = nlohmann::json::parse(m_tag);  // checked when parsed
        w.add_provenance(m_tool, PRT_VERSION, parameters.dump());
    }
    return w.write(m_output);
}

void PoolStep::write_stats(nlohmann::json stats) const {
    if (m_stats.empty()) return;
    stats["tool"] = m_tool;
    write_json_file(m_stats, stats);
}

void PoolStep::note(const char* format, ...) const {
    if (m_common.quiet) return;
    va_list args;
    va_start(args, format);
    vnote(format, args);
    va_end(args);
}

ScenePools scene_pools(const scene::Scene& sc,
                       const std::function<void(const std::filesystem::path&)>& placed_again) {
    ScenePools pools;
    for (const scene::Model& m : sc.models) {
        const std::filesystem::path p = std::filesystem::weakly_canonical(m.pool);
        const auto it = std::find(pools.paths.begin(), pools.paths.end(), p);
        pools.of_model.push_back(static_cast<std::uint32_t>(it - pools.paths.begin()));
        pools.placed_before.push_back(it != pools.paths.end());
        if (it == pools.paths.end())
            pools.paths.push_back(p);
        else if (placed_again)
            placed_again(p);
    }
    std::vector<std::uint32_t> placements(pools.paths.size(), 0);
    for (const std::uint32_t p : pools.of_model) ++placements[p];
    for (std::size_t m = 0; m < sc.models.size(); ++m)
        pools.map_key.push_back(
            placements[pools.of_model[m]] > 1 ? pool::placement_key(sc.models[m].transform) : 0u);
    return pools;
}

}  // namespace prt::tool
