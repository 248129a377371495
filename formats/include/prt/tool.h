// PointRT: what every command-line tool shares: the main() boundary (one-line errors, distinct
// exit codes for usage and runtime errors), --quiet, and (prt/tool_util.h) progress on stderr.
// Include it only from a tool's main translation unit: it brings CLI11.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

#include "prt/tool_util.h"

namespace prt::tool {

/// Options every tool has.
struct CommonOptions {
    bool quiet = false;  ///< --quiet: no progress or statistics on stderr
};

/// Runs a tool: `setup` declares its options on the CLI11 app, `body` does the work once the
/// command line parsed. Usage errors exit 2 with CLI11's message; prt::Error and other exceptions
/// print "TOOL: error: MESSAGE" on one line and exit 1. Returns the exit code for main().
int run(int argc, char** argv, const std::string& tool, const std::string& description,
        const std::function<void(CLI::App&, CommonOptions&)>& setup,
        const std::function<void(const CommonOptions&)>& body);

/// For input files, instead of CLI::ExistingFile: `->check(prt::tool::ExistingInput)`. A missing or
/// unreadable file is then a runtime error in the tools' style ("TOOL: error: PATH: no such file",
/// exit 1; check_input_file), reported by run() once the command line parsed, rather than a usage
/// error in CLI11's wording (exit 2).
extern const CLI::Validator ExistingInput;

}  // namespace prt::tool
