// The prtsub commands. main() forwards argv here; tests call run_cli directly.
#pragma once

namespace prtsub {

//! Runs one prtsub command line. Never throws: errors become one line on stderr.
//! \return 0 on success, 1 for bad input, IO or library failures, 2 for usage errors
int run_cli(int argc, char** argv);

}  // namespace prtsub
