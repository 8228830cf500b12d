// One way for every host tool to run its CLI11 parser (ccmap_cli11, cmake/CcmapHostLibs.cmake):
// --help prints the generated help to stdout; a refused command line prints one line
// "<program>: error: <CLI11's message>" to stderr and asks for exit code 2, the code the tools
// used before CLI11 for usage errors (CLI11's own exit codes are 100 and up).
#pragma once

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <string>

namespace ccmap::tools {

/// Parses argv into `app`'s options. Returns -1 to go on, 0 after --help, 2 after a refusal.
inline int parse_args(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
    return -1;
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    return 0;
  } catch (const CLI::ParseError& e) {
    std::string message = e.what();
    std::replace(message.begin(), message.end(), '\n', ' ');
    std::fprintf(stderr, "%s: error: %s (see %s --help)\n", app.get_name().c_str(), message.c_str(),
                 app.get_name().c_str());
    return 2;
  }
}

}  // namespace ccmap::tools
