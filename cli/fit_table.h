// prtsub eval --fits: the least-squares paper's Table 1 on one mesh.
#pragma once

namespace prtsub {

//! Runs `prtsub eval --fits INPUT ...` (argv[1] == "eval"). Throws like every command.
int cmd_eval_fits(int argc, char** argv);

}  // namespace prtsub
