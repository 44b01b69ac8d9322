// What the command-line tests share beyond the procedural fixtures.
#pragma once

#include <string>
#include <vector>

#include "helpers.h"

namespace prtsub::test {

//! Runs a prtsub command line in-process ("prtsub" is prepended); returns its exit status.
int run_prtsub(std::vector<std::string> args);

}  // namespace prtsub::test
