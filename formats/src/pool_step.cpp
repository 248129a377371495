// One pool-to-pool step of a tool (prt/pool_step.h): options, input, output, provenance, statistics.
#include "prt/pool_step.h"

#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include "prt/atomic_file.h"

namespace prt::tool {

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

}  // namespace prt::tool
