// PointRT: the harness of a pipeline step. A step reads a pool (INPUT), adds or replaces its own
// sections and writes OUTPUT atomically with the input's other sections carried over and one
// provenance record appended; it reports timing and statistics on stderr and, with --stats-json, in
// a JSON file. PoolStep declares the standard options (INPUT, -o/--output, --stats-json; -j through
// add_threads) and does that open -> carry over -> provenance -> atomic write -> statistics once, so
// a tool's main() holds only its own options and logic. Steps without an INPUT pool (importers,
// generators, scene steps) leave the standard options they do not have out (empty help text).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>

#include "prt/error.h"
#include "prt/formats/pool.h"
#include "prt/tool.h"

namespace prt::tool {

/// Writes `stats` (pretty, 2 spaces, newline) to `path`; throws "PATH: cannot write the statistics".
void write_json_file(const std::string& path, const nlohmann::json& stats);

/// Progress of a step in named stages: a new stage finishes the previous bar and starts its own
/// ("TOOL: STAGE"); the total of a stage is taken from its first report.
class StagedProgress {
public:
    StagedProgress(std::string tool, bool quiet) : m_tool(std::move(tool)), m_quiet(quiet) {}
    /// Reports `done` of `total` in `stage`.
    void update(const char* stage, std::uint64_t done, std::uint64_t total);
    /// Finishes the current bar, if any.
    void finish();

private:
    std::string m_tool;
    bool m_quiet;
    std::string m_stage;
    std::unique_ptr<Progress> m_bar;
};

/// One pipeline step's standard options and I/O (see the file comment).
class PoolStep {
public:
    /// Help texts of the standard options; an empty text leaves that option out.
    struct Help {
        std::string input = "Input pool file";  ///< the positional INPUT
        std::string input_name = "input";       ///< its name in the usage line
        std::string output = "Output pool file (written atomically; may equal INPUT)";  ///< -o,--output
        std::string stats = "Also write the statistics as JSON to this file";           ///< --stats-json
    };

    /// Help of a step over a scene (formats/SCENE.md): INPUT is the scene file (input_path(); not
    /// a pool: input() and the carry-over are not for it), no -o (its pools are rewritten in place).
    static Help scene_help(std::string stats) {
        return {.input = "Scene file (formats/SCENE.md); its models need pools with an octree",
                .input_name = "scene",
                .output = "",
                .stats = std::move(stats)};
    }

    /// Help of a step that makes a pool from other input (an importer, a generator): no INPUT
    /// pool and no --stats-json, only -o with `output` as its help.
    static Help generator_help(std::string output = "Pool file to write (replaced atomically)") {
        return {.input = "", .output = std::move(output), .stats = ""};
    }

    PoolStep(std::string tool, std::string description, Help help);
    PoolStep(std::string tool, std::string description)
        : PoolStep(std::move(tool), std::move(description), Help{}) {}

    /// Runs the tool through prt::tool::run: declares INPUT and -o (required unless
    /// output_unused_when() says otherwise), then the step's own `options`, then --stats-json;
    /// `body` runs once the command line parsed, with the clock started.
    /// Returns main()'s exit code.
    int run(int argc, char** argv, const std::function<void(CLI::App&)>& options,
            const std::function<void(PoolStep&)>& body);

    /// Declares -j,--threads on `threads` (0 = every core the process may use).
    template <class T>
    static CLI::Option* add_threads(
        CLI::App& app, T& threads,
        const std::string& help = "Worker threads (0 = every core the process may use)") {
        return app.add_option("-j,--threads", threads, help);
    }
    /// The out-of-core tools' --memory SIZE (tool::memory_limit() reads it; empty: the default),
    /// checked by tool::parse_byte_size when parsed; `help` says what the memory bounds and its default.
    static CLI::Option* add_memory(CLI::App& app, std::string& text, const std::string& help);

    /// Declares an optional -o,--output here (for steps that give Help::output empty): without
    /// one, OUTPUT is INPUT (rewritten in place).
    CLI::Option* add_output(CLI::App& app, const std::string& help);
    /// For a step some of whose runs write no OUTPUT (prt-bricks --stage cells): once the command
    /// line parsed, `unused` says why this run writes none ("" when it does write one). Then -o may be
    /// left out, and a -o given is ignored (not checked, output_path() empty) with the note
    /// "TOOL: -o OUTPUT ignored: WHY" (unless --quiet); when `unused` returns "", -o is required as
    /// for every step (the usage error "--output is required"). Call it from run()'s `options`;
    /// it takes the app's parse_complete_callback.
    void output_unused_when(std::function<std::string()> unused);
    /// For a step some of whose runs never read INPUT (prt-bricks --stage cells reads only its
    /// --cells-folder): once the command line parsed, `unused` says why this run reads none ("" when
    /// it does). Then INPUT is not checked, so a worker need not see the file; input() must not be
    /// called. Call it from run()'s `options`.
    void input_unused_when(std::function<std::string()> unused);

    const std::string& tool() const { return m_tool; }
    bool quiet() const { return m_common.quiet; }
    const std::string& input_path() const { return m_input; }
    const std::string& output_path() const { return m_output; }
    const std::string& stats_path() const { return m_stats; }
    /// --provenance-tag: JSON text recorded as "tag" in this step's provenance parameters (empty:
    /// none). Batch tools (scripts/prt-batch) put there what they need to recognise their own
    /// results: the input's content hash and the arguments of the chain of steps.
    const std::string& provenance_tag() const { return m_tag; }

    /// INPUT, opened (and validated) on first use.
    const pool::PoolFile& input();
    /// The writer of OUTPUT; INPUT's sections are carried over on first use when the step has one.
    pool::PoolWriter& writer();
    /// Removes `types` from writer() (sections that what the step writes makes stale); returns
    /// whether any of them was there, for the step's note.
    bool drop_sections(std::initializer_list<pool::SectionType> types);
    /// Throws "OUTPUT: cannot write: folder F does not exist" (to fail before a long build).
    void check_output_folder() const;
    /// Appends the provenance record {tool, version, `parameters`} and writes OUTPUT atomically
    /// (PoolWriter::write). With --provenance-tag, `parameters` (a JSON object) gets "tag" set to
    /// the tag's JSON value. Returns the bytes written.
    std::uint64_t write(const nlohmann::json& parameters);
    /// write() with the parameters given as JSON object text.
    std::uint64_t write(const std::string& parameters_json);

    /// Seconds since the body started.
    double seconds() const { return now_seconds() - m_start; }
    /// With --stats-json: writes `stats` with "tool" set to the tool's name.
    void write_stats(nlohmann::json stats) const;
    /// note() unless --quiet.
    void note(const char* format, ...) const __attribute__((format(printf, 2, 3)));

    /// Runs `f`; a prt::Error it throws comes out prefixed with "INPUT: ".
    template <class F>
    decltype(auto) about_input(F&& f) const {
        try {
            return std::forward<F>(f)();
        } catch (const Error& e) {
            throw Error(m_input + ": " + e.what());
        }
    }

private:
    std::string m_tool, m_description;
    Help m_help;
    CommonOptions m_common;
    std::string m_input, m_output, m_stats, m_tag;
    double m_start = 0;
    bool m_output_in_place = false;                ///< add_output(): OUTPUT defaults to INPUT
    std::function<std::string()> m_output_unused;  ///< output_unused_when()
    std::function<std::string()> m_input_unused;   ///< input_unused_when()
    std::string m_ignored_output;                  ///< a -o that this run does not write
    std::optional<pool::PoolFile> m_in;
    std::optional<pool::PoolWriter> m_writer;
};

}  // namespace prt::tool
