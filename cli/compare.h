// prtsub compare: uniform against adaptive refinement on one input, as a table, plots and frames.
#pragma once

namespace prtsub {

//! Runs `prtsub compare ...` (argv[1] == "compare"). Throws like every command.
int cmd_compare(int argc, char** argv);

}  // namespace prtsub
