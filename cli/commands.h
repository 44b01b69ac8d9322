// The prtsub commands. main() forwards argv here; tests call run_cli directly.
#pragma once

namespace prtsub {

//! Runs one prtsub command line. Never throws: errors become one line on stderr.
//! \return 0 on success, 1 for bad input, IO or library failures, 2 for usage errors
int run_cli(int argc, char** argv);

// Each command takes the whole argv (argv[1] is its name) and returns an exit code; it may
// throw, and run_cli turns the exception into one line.
int cmd_bench(int argc, char** argv);      //!< bench.cpp
int cmd_render(int argc, char** argv);     //!< render.cpp
int cmd_compare(int argc, char** argv);    //!< compare.cpp
int cmd_eval_fits(int argc, char** argv);  //!< fit_table.cpp
int cmd_view(int argc, char** argv);       //!< view.cpp

}  // namespace prtsub
