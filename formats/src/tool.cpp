// The main() boundary of every tool (prt/tool.h): CLI11 parsing, one-line errors, exit codes.
#include "prt/tool.h"

#include <cstdio>
#include <exception>
#include <new>
#include <string>
#include <vector>

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

}  // namespace prt::tool
