// The ccmap command-line tool as a function, so that tests run it in-process.
#pragma once

#include <ostream>

namespace ccmap::tools {

/// Runs `ccmap <argv[1..]>`: normal output to `out`, errors as one line "ccmap: error: ..." to
/// `err`. Returns the process exit code (0 success, 1 bad input or failure, 2 usage error).
int run_cli(int argc, char** argv, std::ostream& out, std::ostream& err);

}  // namespace ccmap::tools
